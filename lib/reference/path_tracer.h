/// @file path_tracer.h
/// @brief `--method pathtrace`, the truth of light scattered many times: paths through the
///        field the raymarch reference integrates (trilinear density, --cutoff, material colour),
///        sampled by delta tracking (Woodcock) against the grid's largest density, scattering
///        with the Henyey-Greenstein phase up to --bounces times after the first, each scattering
///        event lit by next-event estimation towards every light with physical shadows
///        (exp(-optical depth), gain 0: Cycles' law) by ratio tracking; the ambient light
///        becomes a uniform environment the medium shadows (docs/lighting.md#the-path-traced-truth).
#pragma once

#include "source/source.h"
#include "support/progress.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_stats.h>

namespace vdb_ewa {
namespace detail {

/// settings.pathSamples paths per pixel, spread over the pixel's square (Halton points rotated
/// per pixel), averaged: the beauty, its alpha 1 - the camera ray's transmittance (ratio
/// tracking), the transmittance pass and Z (the pixel centre's ray, as the raymarch's).
/// Channels whose extinction differs are traced one at a time. Deterministic: the same image for any thread count. @throw ValueError for level sets,
/// non-affine grids, emission grids, motion blur, depth of field and the shadow, emission and
/// deep passes. @a progress: one unit per row; throws Cancelled.
Frame pathTrace(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings, const PassRequest& passes,
    RenderStats& stats, Progress* progress = nullptr);

} // namespace detail
} // namespace vdb_ewa
