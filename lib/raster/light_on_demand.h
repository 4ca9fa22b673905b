/// @file light_on_demand.h
/// @brief Light on demand (docs/architecture.md#light-on-demand): before a slab of a screen
///        tile is lit, the light-map rays its live pixels' lookups read are marched, and no
///        others (LightMap::ensureMarched). The lookups lie on the pixel rays of a screen
///        rectangle, between two slab distances: in the frustum piece over the rectangle between
///        two planes of camera depth (a perspective camera's slabs are distances along the ray:
///        the near plane is taken at the nearer distance times the rectangle's smallest
///        cos(theta), the far one at the farther distance times its largest), whose eight
///        corners bound it in the light map's (linear) coordinates.
#pragma once

#include "shading/shading.h"

#include <vdb_ewa/camera.h>

namespace vdb_ewa {
namespace detail {

/// The box of @a map's coordinates [@a lo, @a hi] holding every point that a lookup on a ray
/// through the raster rectangle with corners (@a x0, @a y0) and (@a x1, @a y1) (the first and
/// last rays' positions: a pixel x's centre is x + 1/2) reads at a slab coordinate between @a z0
/// and @a z1 (distance along the ray for a perspective @a camera, camera depth for an
/// orthographic one), with a hundredth of a ray's spacing more for rounding (u, v; w as computed).
void lookupBox(const Camera& camera, const LightMap& map, double x0, double y0, double x1, double y1, double z0, double z1, Vec3d& lo, Vec3d& hi);

} // namespace detail
} // namespace vdb_ewa
