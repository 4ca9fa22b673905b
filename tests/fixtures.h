/// @file fixtures.h
/// @brief Analytic grids built in code, temporary folders, image metrics, external tools.
#pragma once

#include "source/source.h"

#include <vdb_ewa/openvdb_grid.h>
#include <vdb_ewa/vdb_ewa.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>

namespace vdb_ewa::test {

/// Latency bounds are the product's, asserted by the Release suite. The ASan+UBSan suite runs
/// the same tests 2-10x slower, sharing two cores with another test: its bounds are this many
/// times as loose (a stop is still bounded there, and still leaves nothing behind).
#if defined(__SANITIZE_ADDRESS__)
constexpr double kLatencySlack = 2.0;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr double kLatencySlack = 2.0;
#else
constexpr double kLatencySlack = 1.0;
#endif
#else
constexpr double kLatencySlack = 1.0;
#endif

/// A fresh temporary folder, removed with its contents at destruction.
class TempDir
{
public:
    TempDir()
    {
        std::string tmpl = (std::filesystem::temp_directory_path() / "vdb_ewa_test_XXXXXX").string();
        mPath = ::mkdtemp(tmpl.data());
    }
    ~TempDir() { std::filesystem::remove_all(mPath); }
    std::string file(const std::string& name) const { return (std::filesystem::path(mPath) / name).string(); }

private:
    std::string mPath;
};

/// Fog volume with the active voxels [lo, hi] (inclusive index bounds) of value @a density(ijk).
inline openvdb::FloatGrid::Ptr makeFogGrid(const openvdb::Coord& lo, const openvdb::Coord& hi,
    const std::function<float(const openvdb::Coord&)>& density, double voxelSize)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setName("density");
    auto acc = grid->getAccessor();
    for (int i = lo.x(); i <= hi.x(); ++i)
        for (int j = lo.y(); j <= hi.y(); ++j)
            for (int k = lo.z(); k <= hi.z(); ++k) acc.setValueOn(openvdb::Coord(i, j, k), density(openvdb::Coord(i, j, k)));
    return grid;
}

/// Box of active voxels [lo, hi] (inclusive index bounds) of constant @a density.
inline openvdb::FloatGrid::Ptr makeBoxGrid(const openvdb::Coord& lo, const openvdb::Coord& hi, float density,
    double voxelSize)
{
    return makeFogGrid(lo, hi, [density](const openvdb::Coord&) { return density; }, voxelSize);
}

inline void writeGrid(const openvdb::GridBase::Ptr& grid, const std::string& path)
{
    openvdb::io::File file(path);
    file.write({grid});
    file.close();
}

/// Sum of alpha over the image.
inline double alphaSum(const Image& image)
{
    double s = 0.0;
    for (std::size_t i = 3; i < image.rgba.size(); i += 4) s += image.rgba[i];
    return s;
}

/// Intersection over union of the masks alpha > threshold.
inline double alphaMaskIoU(const Image& a, const Image& b, float threshold = 0.05f)
{
    std::size_t inter = 0, uni = 0;
    for (std::size_t i = 3; i < a.rgba.size(); i += 4) {
        const bool ma = a.rgba[i] > threshold, mb = b.rgba[i] > threshold;
        inter += (ma && mb);
        uni += (ma || mb);
    }
    return uni ? double(inter) / double(uni) : 1.0;
}

/// Root-mean-square difference of channel @a c (0..3), or of all four when c < 0.
inline double rmse(const Image& a, const Image& b, int c = -1)
{
    double s = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.rgba.size(); ++i) {
        if (c >= 0 && int(i % 4) != c) continue;
        const double d = double(a.rgba[i]) - double(b.rgba[i]);
        s += d * d;
        ++n;
    }
    return std::sqrt(s / double(n));
}

/// Largest absolute difference of any channel of any pixel.
inline double maxAbsDiff(const Image& a, const Image& b)
{
    double m = 0.0;
    for (std::size_t i = 0; i < a.rgba.size(); ++i) m = std::max(m, std::abs(double(a.rgba[i]) - double(b.rgba[i])));
    return m;
}

/// Path of vdb_render, or empty if it is not installed.
inline std::string vdbRenderPath()
{
    for (const char* p : {"/usr/bin/vdb_render", "/usr/local/bin/vdb_render"}) {
        if (::access(p, X_OK) == 0) return p;
    }
    return "";
}

/// Folder of the shared real-world assets, or empty if absent ($VDB_EWA_ASSETS overrides).
inline std::string assetsDir()
{
    const char* env = std::getenv("VDB_EWA_ASSETS");
    const std::string dir = env ? env : VDB_EWA_DEFAULT_ASSETS;
    return std::filesystem::is_directory(dir) ? dir : "";
}

/// A narrow-band level set (3 voxels each side) of the signed distance @a sdf, sampled in the
/// index box [lo, hi] with voxel size @a h.
inline openvdb::FloatGrid::Ptr makeLevelSet(const std::function<double(const Vec3d&)>& sdf, const openvdb::Coord& lo,
    const openvdb::Coord& hi, double h)
{
    const float band = float(3.0 * h);
    auto grid = openvdb::FloatGrid::create(band);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    auto acc = grid->getAccessor();
    for (int i = lo.x(); i <= hi.x(); ++i)
        for (int j = lo.y(); j <= hi.y(); ++j)
            for (int k = lo.z(); k <= hi.z(); ++k) {
                const double d = sdf(Vec3d(i, j, k) * h);
                if (std::abs(d) < band) acc.setValueOn(openvdb::Coord(i, j, k), float(d));
                else acc.setValueOff(openvdb::Coord(i, j, k), d < 0 ? -band : band);
            }
    return grid;
}

/// A fog of density @a peak inside the surface @a sdf = 0 (world units), falling linearly to 0
/// across 4 voxels around it (@a peak / 2 on the surface, so central differences and Newton
/// steps near it are exact), sampled at the voxel centres of [-n, n]^3 and active where it is
/// above 0, as a fog is: for --iso surfaces of known shape.
inline openvdb::FloatGrid::Ptr makeFogAround(const std::function<double(const Vec3d&)>& sdf, double peak, int n, double h)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setName("density");
    auto acc = grid->getAccessor();
    for (int i = -n; i <= n; ++i)
        for (int j = -n; j <= n; ++j)
            for (int k = -n; k <= n; ++k) {
                const double density = peak * std::clamp(0.5 - sdf(Vec3d(i, j, k) * h) / (4.0 * h), 0.0, 1.0);
                if (density > 0.0) acc.setValueOn(openvdb::Coord(i, j, k), float(density));
            }
    return grid;
}

inline openvdb::FloatGrid::Ptr sphereLevelSet(double radius, double h)
{
    const int n = int(std::ceil(radius / h)) + 4;
    return makeLevelSet([=](const Vec3d& p) { return glm::length(p) - radius; }, openvdb::Coord(-n), openvdb::Coord(n), h);
}

/// Settings for a pure absorber with no cutoffs: transmittance tests.
inline RenderSettings absorberSettings(double sigma)
{
    RenderSettings s;
    s.medium.absorb = Vec3d(sigma);
    s.medium.scatter = Vec3d(0.0);
    s.cutoff = 0.0;
    s.threads = 0;
    return s;
}

/// A white scatterer (extinction @a sigma, no absorption) lit from the camera's side (+z) by a
/// white light, with no gain or cutoff and fine shadow and reference steps: seen down -z, the
/// closed form C = albedo L (1 - exp(-2 tau)) / 2 of a slab holds whatever its profile.
inline RenderSettings scatteringSlabSettings(double sigma)
{
    RenderSettings s;
    s.medium.absorb = Vec3d(0.0);
    s.medium.scatter = Vec3d(sigma);
    s.lights[0].direction = Vec3d(0, 0, 1);
    s.lights[0].color = Vec3d(1.0);
    s.shadow.gain = 0.0;
    s.cutoff = 0.0;
    s.shadow.step = 0.1;
    s.step = 0.25;
    return s;
}

} // namespace vdb_ewa::test

namespace vdb_ewa::test {

/// Render an in-memory grid.
inline Image renderGrid(const openvdb::GridBase::Ptr& grid, const CameraSettings& camera,
    const RenderSettings& settings, RenderStats* stats = nullptr)
{
    const GridSource source = gridSourceFromOpenVDB(grid);
    return Renderer(settings).render(source, Camera(camera, source.worldCentre()), stats);
}

/// Perspective camera on the sample cloud (makeSampleGrid), from (1, 0.5, 4).
inline Camera cloudCamera(const GridSource& cloud, int width, int height)
{
    CameraSettings cam;
    cam.width = width;
    cam.height = height;
    cam.translate = Vec3d(1.0, 0.5, 4.0);
    return Camera(cam, cloud.worldCentre());
}

/// A perspective camera of @a w x @a h pixels at @a eye looking at @a target.
inline CameraSettings lookAtCamera(const Vec3d& eye, const Vec3d& target, int w, int h)
{
    CameraSettings c;
    c.width = w;
    c.height = h;
    c.translate = eye;
    c.lookAt = target;
    return c;
}

/// Orthographic camera looking down -z at (x, y), from above z.
inline CameraSettings orthoDownZ(double x, double y, double z, double frame, int res)
{
    CameraSettings c;
    c.projection = Projection::Orthographic;
    c.width = c.height = res;
    c.translate = Vec3d(x, y, z);
    c.lookAt = Vec3d(x, y, z - 1.0);
    c.frame = frame;
    return c;
}

} // namespace vdb_ewa::test
