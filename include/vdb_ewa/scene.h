/// @file scene.h
/// @brief A scene that stays loaded: a grid and the settings, rendered from one camera after
///        another (a viewport, a turntable). What a render can reuse from the renders before
///        it, it reuses; what a change of settings invalidates is made anew; the image is the
///        one a Renderer makes of the same grid, settings and camera, bit for bit
///        (docs/api.md#scenes-what-a-render-reuses).
#pragma once

#include <memory>

#include "camera.h"
#include "export.h"
#include "frame.h"
#include "grid_source.h"
#include "interrupter.h"
#include "render_settings.h"
#include "render_stats.h"

namespace vdb_ewa {

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
    const RenderSettings& settings() const;
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

    /// Let go of everything kept: the next render starts cold.
    void clear();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace vdb_ewa
