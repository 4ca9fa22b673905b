/// @file scene.h
/// @brief A scene that stays loaded: a grid and the settings, rendered from one camera after
///        another (a viewport, a turntable). What a render can reuse from the renders before
///        it, it reuses; what a change of settings invalidates is made anew; the image is the
///        one a Renderer makes of the same grid, settings and camera, bit for bit
///        (docs/api.md#scenes-what-a-render-reuses).
#pragma once

#include <functional>
#include <memory>

#include "camera.h"
#include "export.h"
#include "frame.h"
#include "grid_source.h"
#include "interrupter.h"
#include "render_settings.h"
#include "render_stats.h"

namespace vdb_ewa {

/// A progressive render's images (docs/api.md#progressive-refinement), called on the thread
/// that called Scene::render: first the coarse image (@a stats.coarseScale n > 1: draft's
/// knobs at one sample an n x n block of pixels, interpolated back to the camera's width x
/// height; no deep samples), then the image of the asked settings (coarseScale 1), the one
/// render returns. An image too small for a coarse one (under 32 pixels a side) gets only the
/// second. To stop, cancel the render's Interrupter (a callback that throws stops it too).
using ProgressiveCallback = std::function<void(const Frame& frame, const RenderStats& stats)>;

class VDB_EWA_API Scene
{
public:
    /// @throw ValueError if a setting is out of range (RenderSettings::validate).
    Scene(GridSource grid, const RenderSettings& settings);
    ~Scene();
    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    const GridSource& grid() const;
    /// A copy, taken under the scene's lock (setSettings may run on another thread).
    RenderSettings settings() const;
    /// The settings of the renders to come. What they change is made anew at the next render
    /// (docs/api.md#scenes-what-a-render-reuses); the rest is kept.
    /// @throw ValueError if a setting is out of range.
    void setSettings(const RenderSettings& settings);

    /// Render the grid through @a camera: Renderer(settings()).renderFrame(grid(), camera,
    /// passes, ...) bit for bit, reusing what earlier renders made (RenderStats::lightMapsReused,
    /// lightRaysReused). One render at a time: a call made while another runs waits for it.
    /// A render that throws (Cancelled included) leaves nothing kept.
    /// @throw Cancelled, ValueError as Renderer::renderFrame.
    Frame render(const Camera& camera, const PassRequest& passes = PassRequest{}, RenderStats* stats = nullptr,
        Interrupter* interrupter = nullptr);
    /// The same with @a settings for this render only (the scene's stay as they are): what
    /// they share with the renders before it is reused all the same.
    /// @throw ValueError if a setting is out of range; Cancelled.
    Frame render(const Camera& camera, const RenderSettings& settings, const PassRequest& passes = PassRequest{},
        RenderStats* stats = nullptr, Interrupter* interrupter = nullptr);

    /// Progressive refinement: as above, with @a progressive called with a coarse image first,
    /// then with the frame returned. Both share what the scene keeps (the coarse image marches
    /// the light rays the asked one reads). @a interrupter sees one rising progress: the coarse
    /// image takes its first 10 %; a cancel between or during them stops at once.
    /// @throw ValueError, Cancelled, and what @a progressive throws.
    Frame render(const Camera& camera, const RenderSettings& settings, const ProgressiveCallback& progressive,
        const PassRequest& passes = PassRequest{}, RenderStats* stats = nullptr, Interrupter* interrupter = nullptr);

    /// Let go of everything kept: the next render starts cold.
    void clear();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace vdb_ewa
