/// @file coarse_image.h
/// @brief The coarse image of a progressive render (Scene::render with a ProgressiveCallback,
///        docs/api.md#progressive-refinement): draft's speed knobs at one sample an n x n block
///        of pixels, interpolated back to the camera's pixels (Camera::withPixelSize,
///        detail::upsampled): what a viewport draws while the user drags, before the image of
///        the asked settings.
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/render_settings.h>

namespace vdb_ewa {
namespace detail {

/// The coarse image's pixel size n: one sample a kCoarseScale x kCoarseScale block (1/16 of
/// the samples), smaller where the image would keep fewer than kCoarseSide samples a side; 1
/// (no coarse image: the asked one comes at once) for images that small.
inline constexpr int kCoarseScale = 4;
inline constexpr int kCoarseSide = 16;
int coarseScale(const Camera& camera);

/// The settings of the coarse image of a render with @a asked: draft's knobs
/// (RenderSettings::preset(Quality::Draft): splatting, the light maps' step and spacing,
/// motion blur, the lens) but the asked --lod-error, and everything else the asked settings'
/// (the optical model, the lights). Its light maps are coarser than the asked image's: a
/// Scene keeps both sets (pyro at 480x270: a new scene's coarse image marches 1,248 rays, the
/// asked image 3,216). Draft's knobs balance: with the asked light maps, draft's level of
/// detail alone renders pyro's coarse image 34 % brighter than the asked one, with draft's
/// maps and the asked --lod-error 5 % (docs/api.md#progressive-refinement).
RenderSettings coarseSettings(const RenderSettings& asked);

/// True where the coarse image's light maps are the asked image's (asked for with draft's light
/// maps, as `--quality draft` is): the two images share one set.
bool coarseLightsAreAsked(const RenderSettings& asked);

} // namespace detail
} // namespace vdb_ewa
