/// @file plugin_example.cpp
/// @brief A host ("plugin-style") that renders a grid it already holds in memory with the
///        installed vdb_ewa package: no file round trip, the frame stays in memory, progress
///        is shown and a render is cancelled from the host's UI thread. Built and run by the
///        ctest install.consumer; exits non-zero if anything is not as expected.
#include <vdb_ewa/openvdb_grid.h>
#include <vdb_ewa/vdb_ewa.h>

#include <openvdb/openvdb.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <future>
#include <mutex>

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

/// The host's progress display (a status bar, Houdini's UT_Interrupt, Nuke's progress).
/// wasInterrupted() runs on the render's worker threads, but never two calls at once, so the
/// counters need no lock; the mutex only serves waitForFirstReport() on another thread.
class HostProgress : public vdb_ewa::Interrupter
{
public:
    void start(const char* name) override
    {
        std::printf("  render of '%s' started\n", name);
        lastPercent = -1;
        rising = true;
    }
    bool wasInterrupted(int percent) override
    {
        if (percent < lastPercent) rising = false;
        lastPercent = percent;
        {
            std::lock_guard<std::mutex> lock(mMutex);
            mReported = true;
        }
        mReport.notify_all();
        return false; // a host whose UI is polled (not a separate thread) returns "Esc pressed" here
    }
    void end() override { std::printf("  render ended at %d %%\n", lastPercent); }

    /// Block the calling (UI) thread until the render has reported progress once.
    void waitForFirstReport()
    {
        std::unique_lock<std::mutex> lock(mMutex);
        mReport.wait(lock, [this] { return mReported; });
    }

    int lastPercent = -1;
    bool rising = true;

private:
    std::mutex mMutex;
    std::condition_variable mReport;
    bool mReported = false;
};

bool fail(const char* what)
{
    std::fprintf(stderr, "plugin_example: %s\n", what);
    return false;
}

/// Render the beauty with a depth and a transmittance pass into memory, with progress.
bool renderWithPasses(const vdb_ewa::GridSource& grid, const vdb_ewa::Camera& camera)
{
    vdb_ewa::RenderSettings settings;  // vdb_render's optical model and defaults
    settings.threads = 2;              // this render's own tbb::task_arena; 0 = the caller's
    vdb_ewa::PassRequest passes;
    passes.depth = true;
    passes.transmittance = true;
    HostProgress progress;
    vdb_ewa::RenderStats stats;
    const vdb_ewa::Frame frame = vdb_ewa::Renderer(settings).renderFrame(grid, camera, passes, &stats, &progress);

    // Premultiplied RGBA, row 0 at the top: the ball covers the middle of the frame, not its corners.
    const vdb_ewa::Image& image = frame.beauty;
    const int x = image.width / 2, y = image.height / 2;
    const std::size_t centre = std::size_t(y) * std::size_t(image.width) + std::size_t(x);
    const float alpha = image.pixel(x, y)[3];
    const float cornerAlpha = image.pixel(0, 0)[3];
    const float depth = frame.depth[centre];                 // camera-space depth, world units
    const float transmittance = frame.transmittance[3 * centre]; // red channel
    std::printf("  %dx%d: alpha %.3f in the middle (depth %.2f, transmittance %.3f), %.3f in the corner\n",
        image.width, image.height, alpha, depth, transmittance, cornerAlpha);
    if (!(alpha > 0.5f) || cornerAlpha != 0.0f) return fail("unexpected beauty");
    // The ball's front is 4 units from the camera, its centre 5.
    if (!(depth > 4.0f && depth < 5.0f)) return fail("unexpected depth");
    // Grey extinction: alpha = 1 - transmittance.
    if (!(std::abs(transmittance - (1.0f - alpha)) < 0.01f)) return fail("unexpected transmittance");
    if (progress.lastPercent != 100 || !progress.rising) return fail("progress did not rise to 100 %");
    return true;
}

/// Render on a background thread, as a plugin does, and cancel it from this (UI) thread.
bool cancelFromTheUiThread(const vdb_ewa::GridSource& grid, const vdb_ewa::Camera& camera)
{
    const vdb_ewa::Renderer renderer(vdb_ewa::RenderSettings::preset(vdb_ewa::Quality::High));
    HostProgress progress;
    std::future<vdb_ewa::Image> render =
        std::async(std::launch::async, [&] { return renderer.render(grid, camera, nullptr, &progress); });
    progress.waitForFirstReport();
    const auto cancelled = std::chrono::steady_clock::now();
    progress.cancel(); // thread-safe (an atomic store); also safe in a signal handler
    try {
        render.get();
        return fail("the render finished although it was cancelled");
    } catch (const vdb_ewa::Cancelled&) { // nothing to clean up: the partial image is discarded
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - cancelled).count();
        std::printf("  cancelled: the render stopped %.1f ms after cancel()\n", ms);
        if (ms > 1000.0) return fail("the render took too long to stop");
    }
    progress.reset(); // the interrupter may serve the next render
    return true;
}

} // namespace

int main()
{
    try {
        openvdb::initialize(); // the host's own OpenVDB set-up (vdb_ewa needs nothing global)
        std::printf("vdb_ewa %s\n", vdb_ewa::versionString());

        // Wrap the host's grid (shared, not copied) as the renderer's input.
        const vdb_ewa::GridSource grid = vdb_ewa::gridSourceFromOpenVDB(makeFogBall(1.0, 0.02));

        // A perspective camera 5 units in front of the ball, looking at its centre.
        vdb_ewa::CameraSettings cameraSettings;
        cameraSettings.width = 320;
        cameraSettings.height = 240;
        cameraSettings.translate = vdb_ewa::Vec3d(0.0, 0.0, 5.0);
        const vdb_ewa::Camera camera(cameraSettings, grid.worldCentre());

        std::printf("render with passes:\n");
        if (!renderWithPasses(grid, camera)) return 1;
        std::printf("render cancelled from the UI thread:\n");
        if (!cancelFromTheUiThread(grid, camera)) return 1;
        return 0;
    } catch (const vdb_ewa::Error& e) { // IoError, InputError, ValueError: one-line messages
        std::fprintf(stderr, "plugin_example: %s\n", e.what());
        return 1;
    }
}
