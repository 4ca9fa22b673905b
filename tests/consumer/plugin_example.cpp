/// @file plugin_example.cpp
/// @brief A host ("plugin-style") that renders a grid it already holds in memory with the
///        installed vdb_ewa package: no file round trip. Built and run by the ctest
///        install.consumer; exits non-zero if the image is not the expected fog ball.
#include <vdb_ewa/openvdb_grid.h>
#include <vdb_ewa/vdb_ewa.h>

#include <openvdb/openvdb.h>

#include <cmath>
#include <cstdio>

namespace {

/// The host's grid: a ball of fog whose density falls linearly from 1 at the origin to 0 at
/// @a radius (world units).
openvdb::FloatGrid::Ptr makeFogBall(double radius, double voxelSize)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelSize));
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setName("density");
    const int n = int(std::ceil(radius / voxelSize));
    auto accessor = grid->getAccessor();
    for (int i = -n; i <= n; ++i) {
        for (int j = -n; j <= n; ++j) {
            for (int k = -n; k <= n; ++k) {
                const double r = voxelSize * std::sqrt(double(i * i + j * j + k * k));
                if (r < radius) accessor.setValue(openvdb::Coord(i, j, k), float(1.0 - r / radius));
            }
        }
    }
    return grid;
}

} // namespace

int main()
{
    try {
        openvdb::initialize(); // the host's own OpenVDB set-up (vdb_ewa needs nothing global)
        std::printf("vdb_ewa %s\n", vdb_ewa::versionString());

        // Wrap the host's grid (shared, not copied) as the renderer's input.
        const vdb_ewa::GridSource grid = vdb_ewa::gridSourceFromOpenVDB(makeFogBall(1.0, 0.05));

        // A small perspective camera 5 units in front of the ball, looking at its centre.
        vdb_ewa::CameraSettings cameraSettings;
        cameraSettings.width = 64;
        cameraSettings.height = 48;
        cameraSettings.translate = vdb_ewa::Vec3d(0.0, 0.0, 5.0);
        const vdb_ewa::Camera camera(cameraSettings, grid.worldCentre());

        // vdb_render's optical model and defaults; threads = 0 uses every core (a task arena).
        const vdb_ewa::RenderSettings settings;
        const vdb_ewa::Image image = vdb_ewa::Renderer(settings).render(grid, camera);

        // Premultiplied RGBA: the ball covers the middle of the frame, not its corners.
        const float centreAlpha = image.pixel(image.width / 2, image.height / 2)[3];
        const float cornerAlpha = image.pixel(0, 0)[3];
        std::printf("%dx%d image: alpha %.3f in the middle, %.3f in the corner\n", image.width,
            image.height, centreAlpha, cornerAlpha);
        if (!(centreAlpha > 0.5f) || cornerAlpha != 0.0f) {
            std::fprintf(stderr, "plugin_example: unexpected image\n");
            return 1;
        }
        return 0;
    } catch (const vdb_ewa::Error& e) { // IoError, InputError, ValueError: one-line messages
        std::fprintf(stderr, "plugin_example: %s\n", e.what());
        return 1;
    }
}
