/// @file renderer.h
/// @brief The renderer: EWA volume splatting (Zwicker et al. 2002) of a GridSource seen by a
///        Camera, composited in image-aligned slabs. The sole orchestrator of the pipeline.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "camera.h"
#include "frame.h"
#include "grid_source.h"
#include "image.h"
#include "interrupter.h"
#include "render_settings.h"
#include "render_stats.h"

namespace vdb_ewa {
namespace detail {
class Progress;
class LightCache;
} // namespace detail

/// The process's peak resident memory in bytes: the high-water mark of its own address space
/// (VmHWM), since it started or since /proc/self/clear_refs last reset it. Not getrusage's
/// maxrss, which keeps the peak of the process that exec'd it: a CLI run from a Python process
/// holding 365 MB reported 365 MB for every render. 0 where /proc cannot be read.
VDB_EWA_API std::uint64_t peakResidentBytes();

class VDB_EWA_API Renderer
{
public:
    /// @throw ValueError if a setting is out of range.
    explicit Renderer(const RenderSettings& settings);

    const RenderSettings& settings() const { return mSettings; }

    /// Render @a grid through @a camera: a fog volume with EWA volume splatting, a level set as
    /// its iso-surface with surface splats (settings.surface.isovalue, settings.surface.shader).
    /// Thread-safe: a Renderer holds no mutable state, so one Renderer (or several) may render
    /// on several threads at once; each render runs in its own tbb::task_arena of
    /// settings.threads threads (0: the caller's arena). The result does not depend on the
    /// thread count (bit-identical).
    /// @param interrupter receives progress and may cancel (optional; see interrupter.h).
    /// @throw Cancelled if @a interrupter cancelled the render.
    Image render(const GridSource& grid, const Camera& camera, RenderStats* stats = nullptr,
        Interrupter* interrupter = nullptr) const;

    /// Render the beauty and the passes in @a passes (docs/output.md); the beauty is the same
    /// image render() returns. @throw ValueError for passes --method raymarch cannot make;
    /// Cancelled as render().
    Frame renderFrame(const GridSource& grid, const Camera& camera, const PassRequest& passes,
        RenderStats* stats = nullptr, Interrupter* interrupter = nullptr) const;

private:
    /// @a grid by its kind and the method: a level set, the reference, sub-frames or one frame.
    VDB_EWA_LOCAL void renderGrid(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    /// Level sets: flattened surface kernels (Sec. 6.3, 6.4) and a z-buffer (Sec. 7.2).
    VDB_EWA_LOCAL void renderLevelSet(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    /// Fog volumes: kernels, shadows, splats (Eq. 29-33), slab compositing.
    /// Fog volumes, streamed: bricks front to back in depth windows, those behind opaque tiles
    /// never expanded; returns with stats.streamed false (nothing done) where it cannot.
    VDB_EWA_LOCAL void renderStreamedFogVolume(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    VDB_EWA_LOCAL void renderFogVolume(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    /// Fog volumes by splatting at one sample a @a size x @a size block of pixels, interpolated
    /// back onto the image's (larger pixels; 1: every pixel).
    VDB_EWA_LOCAL void renderAtPixelSize(const GridSource::Impl& grid, const Camera& camera, int size, const PassRequest& passes,
        Frame& frame, RenderStats& stats, detail::Progress& progress) const;
    /// Fog volumes by splatting, at the sub-pixel samples the voxels' screen size asks for
    /// (SplatOptions::supersample): sub-frames or one frame.
    VDB_EWA_LOCAL void renderSplatted(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    /// Fog volumes in sub-frames (MotionBlur::samples, RenderSettings::lensSamples): each over
    /// its part of the shutter and through its part of the lens, averaged.
    VDB_EWA_LOCAL void renderSubFrames(const GridSource::Impl& grid, const Camera& camera, const PassRequest& passes, Frame& frame,
        RenderStats& stats, detail::Progress& progress) const;
    /// True if the grid has a velocity grid and the shutter is open: motion blur moves its kernels.
    VDB_EWA_LOCAL bool movesOverTheShutter(const GridSource::Impl& grid) const;

    friend class Scene;
    RenderSettings mSettings;
    /// A Scene's light maps, kept between its renders (lib/frame_lights.h); none for a Renderer
    /// of its own. Not owned.
    detail::LightCache* mLightCache = nullptr;
};

} // namespace vdb_ewa
