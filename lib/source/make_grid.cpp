/// @file make_grid.cpp
/// @brief Sample grid generator (vdb_ewa make-grid).
#include <vdb_ewa/make_grid.h>

#include "source/grid_source_impl.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/error.h>
#include <vdb_ewa/openvdb_grid.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace vdb_ewa {
namespace {

struct Blob
{
    Vec3d centre;
    double radius, amplitude;
};

// A lumpy cumulus: a big body, a few lobes, and small puffs for detail.
const std::array<Blob, 9> kBlobs{{
    {{0.0, 0.0, 0.0}, 0.55, 1.0},
    {{0.45, 0.15, 0.1}, 0.35, 0.8},
    {{-0.5, 0.05, -0.1}, 0.38, 0.8},
    {{0.1, 0.45, 0.0}, 0.32, 0.9},
    {{-0.2, 0.35, 0.25}, 0.22, 0.7},
    {{0.3, -0.25, -0.3}, 0.25, 0.6},
    {{-0.15, -0.3, 0.3}, 0.2, 0.6},
    {{0.7, 0.35, -0.2}, 0.15, 0.6},
    {{-0.75, 0.3, 0.2}, 0.14, 0.6},
}};

constexpr double kCloudPeakDensity = 0.35;

/// Map of each sample grid, for the smallest voxel edge @a h.
openvdb::math::Transform::Ptr sampleTransform(SampleGrid kind, double h)
{
    using openvdb::math::Mat4d;
    Mat4d m = Mat4d::identity();
    switch (kind) {
    case SampleGrid::Cloud:
    case SampleGrid::Tiles:
        return openvdb::math::Transform::createLinearTransform(h);
    case SampleGrid::Anisotropic:
        m.setToScale(openvdb::Vec3d(h, 2.0 * h, 4.0 * h));
        break;
    case SampleGrid::Sheared: {
        Mat4d shear = Mat4d::identity();
        shear[1][0] = 0.5; // row-vector convention: x' += 0.5 y
        shear[2][1] = 0.3; // y' += 0.3 z
        Mat4d scale = Mat4d::identity();
        scale.setToScale(openvdb::Vec3d(h));
        Mat4d rot = openvdb::math::rotation<Mat4d>(openvdb::Vec3d(0.3, 1.0, 0.2).unit(), 0.7);
        m = scale * shear * rot;
        break;
    }
    }
    return openvdb::math::Transform::Ptr(new openvdb::math::Transform(
        openvdb::math::MapBase::Ptr(new openvdb::math::AffineMap(m))));
}

} // namespace

SampleGrid sampleGridFromName(const std::string& name)
{
    if (name == "cloud") return SampleGrid::Cloud;
    if (name == "anisotropic") return SampleGrid::Anisotropic;
    if (name == "sheared") return SampleGrid::Sheared;
    if (name == "tiles") return SampleGrid::Tiles;
    throw ValueError("unknown sample grid '" + name + "' (expected cloud, anisotropic, sheared or tiles)");
}

double sampleCloudDensity(const Vec3d& p)
{
    double d = 0.0;
    for (const Blob& b : kBlobs) {
        const Vec3d q = (p - b.centre) / b.radius;
        d += b.amplitude * std::exp(-glm::dot(q, q));
    }
    // Two octaves of smooth product-of-sines detail, so the cloud has billows to shade.
    const double detail = std::sin(7.1 * p.x + 1.3) * std::sin(6.3 * p.y + 0.7) * std::sin(5.7 * p.z + 2.1) +
                          0.5 * std::sin(13.7 * p.x + 0.4) * std::sin(12.9 * p.y + 2.3) * std::sin(14.3 * p.z + 1.1);
    // Soft threshold to [0, 1], scaled to a semi-transparent peak density.
    return kCloudPeakDensity * std::clamp(1.6 * (d * (1.0 + 0.35 * detail) - 0.15), 0.0, 1.0);
}

GridSource makeSampleGrid(SampleGrid kind, double voxelSize)
{
    // The grid spans [-1.2, 1.2]^3: 0.01 gives 240^3 voxels to evaluate (2.6 M active, a few
    // seconds); 0.0025 gives 960^3 (about 164 M active, a few minutes), for bench.py scaling.
    if (!(voxelSize >= 0.0025 && voxelSize <= 2.4)) {
        throw ValueError("make-grid: --voxel-size must be in [0.0025, 2.4] world units");
    }
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(sampleTransform(kind, voxelSize));
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    const auto& xform = grid->transform();

    // Index bounds of the world box [-1.2, 1.2]^3 (conservative through the map's corners).
    openvdb::Vec3d lo(1e30), hi(-1e30);
    for (int c = 0; c < 8; ++c) {
        const openvdb::Vec3d w((c & 1) ? 1.2 : -1.2, (c & 2) ? 1.2 : -1.2, (c & 4) ? 1.2 : -1.2);
        const openvdb::Vec3d i = xform.worldToIndex(w);
        lo = openvdb::math::minComponent(lo, i);
        hi = openvdb::math::maxComponent(hi, i);
    }
    auto acc = grid->getAccessor();
    for (int i = int(std::floor(lo.x())); i <= int(std::ceil(hi.x())); ++i)
        for (int j = int(std::floor(lo.y())); j <= int(std::ceil(hi.y())); ++j)
            for (int k = int(std::floor(lo.z())); k <= int(std::ceil(hi.z())); ++k) {
                const openvdb::Vec3d w = xform.indexToWorld(openvdb::Vec3d(i, j, k));
                double d = sampleCloudDensity(Vec3d(w.x(), w.y(), w.z()));
                // The tiles variant saturates sooner, so whole leaves hold exactly 1.
                if (kind == SampleGrid::Tiles) d = std::min(kCloudPeakDensity, 2.0 * d);
                if (d > 0.0) acc.setValueOn(openvdb::Coord(i, j, k), float(d));
            }
    if (kind == SampleGrid::Tiles) {
        // Leaves whose voxels all saturate at 1 become active tiles.
        openvdb::tools::prune(grid->tree(), /*tolerance=*/0.0f);
    }
    return gridSourceFromOpenVDB(grid);
}

void writeSampleGrid(SampleGrid kind, const std::string& path, double voxelSize)
{
    const GridSource source = makeSampleGrid(kind, voxelSize);
    const std::string tmp = path + ".tmp";
    try {
        openvdb::io::File file(tmp);
        openvdb::GridPtrVec grids{openvdb::ConstPtrCast<openvdb::FloatGrid>(source.impl().grid)};
        file.write(grids);
        file.close();
        std::filesystem::rename(tmp, path);
    } catch (const std::exception& e) {
        std::remove(tmp.c_str());
        throw IoError(path + ": cannot write VDB file (" + std::string(e.what()) + ")");
    }
}

} // namespace vdb_ewa
