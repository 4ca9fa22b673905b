/// @file light_on_demand.h
/// @brief Light on demand (docs/architecture.md#light-on-demand): before a window of the
///        streamed frame is composited, the light-map rays its splats can look up are marked
///        and marched, and no others. A splat is looked up on the pixel rays of its box, in the
///        slabs it overlaps. Those points lie in a frustum piece over the box between two planes
///        of camera depth (a perspective camera's slabs are distances along the ray: the near
///        plane is taken at the nearest slab distance times the box's smallest cos(theta)),
///        whose eight corners bound it in the light map's (linear) coordinates.
#pragma once

#include "projection/projection.h"
#include "shading/shading.h"

#include <vdb_ewa/camera.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// Whether every screen tile of the inclusive tile rectangle (tx0, ty0, tx1, ty1) is opaque
/// (StreamedRaster::hidden).
using TilesOpaque = std::function<bool(int tx0, int ty0, int tx1, int ty1)>;

/// Mark and march, in each of @a lights, the rays @a window's splats can look up. Returns the
/// tiles of rays marched. @a progress: checked for cancellation (throws Cancelled).
/// @a opaque: where given, a splat whose tiles are all opaque already marks nothing (none of
/// its pixels composites again: pig from its README camera marches 35,088 rays instead of
/// 42,000, docs/performance.md#the-streamed-frame---cull-1920x1080).
std::uint64_t lightWindow(const SplatSet& window, const Camera& camera, std::vector<LightMap>& lights, Progress* progress,
    const TilesOpaque& opaque = {});

} // namespace detail
} // namespace vdb_ewa
