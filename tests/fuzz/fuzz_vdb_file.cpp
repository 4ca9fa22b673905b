/// @file fuzz_vdb_file.cpp
/// @brief libFuzzer harness over the reading path: the input is a .vdb file. Whatever
///        GridSource::open accepts is framed by a small camera and rendered (kernel extraction,
///        shadows, projection, rasterisation), under a small memory budget. vdb_ewa::Error is the
///        expected way to refuse; a crash, a sanitizer report, any other exception, a timeout or
///        more memory than -rss_limit_mb is a finding (tests/fuzz/README.md).
#include <vdb_ewa/vdb_ewa.h>

#include "source/source.h"

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

namespace {

/// A 48x32 perspective view of @a grid's active bounding box from +z (its centre if empty).
vdb_ewa::Camera framing(const vdb_ewa::GridSource& grid)
{
    vdb_ewa::CameraSettings cam;
    cam.width = 48;
    cam.height = 32;
    const openvdb::CoordBBox box = grid.impl().grid->evalActiveVoxelBoundingBox();
    double radius = 1.0;
    if (!box.empty()) {
        const vdb_ewa::Vec3d lo = grid.impl().indexToWorld(vdb_ewa::Vec3d(box.min().x(), box.min().y(), box.min().z()));
        const vdb_ewa::Vec3d hi = grid.impl().indexToWorld(vdb_ewa::Vec3d(box.max().x(), box.max().y(), box.max().z()));
        radius = std::max(0.5 * glm::length(hi - lo), 1e-6);
    }
    const vdb_ewa::Vec3d centre = grid.worldCentre();
    cam.translate = centre + vdb_ewa::Vec3d(0.0, 0.0, 3.0 * radius);
    cam.lookAt = centre;
    return vdb_ewa::Camera(cam, centre);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static const std::string path = "/tmp/vdb_ewa_fuzz_" + std::to_string(::getpid()) + ".vdb";
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        const vdb_ewa::GridSource grid = vdb_ewa::GridSource::open(path);
        vdb_ewa::RenderSettings settings;
        settings.threads = 1;
        settings.maxMemory = std::uint64_t(256) << 20;
        vdb_ewa::Renderer(settings).render(grid, framing(grid));
    } catch (const vdb_ewa::Error&) {
        // a clean refusal: the file, the grid or the frame is out of bounds
    }
    std::remove(path.c_str());
    return 0;
}
