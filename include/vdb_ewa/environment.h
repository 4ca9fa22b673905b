/// @file environment.h
/// @brief A latitude-longitude environment as a low-order fill: the sphere cut into cells around
///        evenly spread directions, each cell's light one directional light (with its own
///        shadows, so the fill is occluded; docs/lighting.md#environment).
#pragma once

#include "image.h"
#include "render_settings.h"

#include <string>
#include <vector>

namespace vdb_ewa {

/// Direction (unit, world, +Y up) of the point (@a u, @a v) of a latitude-longitude image, both
/// in [0, 1]: OpenEXR's latitude-longitude map, which USD's DomeLight (Karma, Solaris) follows:
/// longitude pi (1 - 2u), latitude pi (1/2 - v); v = 0 is +Y (the top row), u = 0.5 faces +Z,
/// u = 0.25 faces +X.
VDB_EWA_API Vec3d latLongDirection(double u, double v);

/// The environment @a latlong (RGB radiance; alpha ignored) as @a count directional lights: the
/// sphere split into the cells nearest to @a count directions of a Fibonacci lattice, each
/// cell's light a light along its radiance-weighted mean direction whose colour is
/// intensity x its radiance integrated over the cell's solid angle / 4 pi. A uniform
/// environment of radiance A so gives lights whose colours sum to A: what --ambient A scatters
/// where nothing shadows. Lights of zero colour are dropped.
/// @throw ValueError for an empty image, count outside [1, kMaxLights] or a negative or
///        non-finite intensity.
VDB_EWA_API std::vector<Light> environmentLights(const Image& latlong, int count, double intensity = 1.0);

/// Read a latitude-longitude image (any format OpenImageIO reads: .exr, .hdr, ...) as linear RGB
/// radiance, as stored (no colour conversion). Non-finite and negative values read as 0.
/// @throw IoError (missing, unreadable or not an image), ValueError (not 2:1 within 1 %).
VDB_EWA_API Image readLatLongImage(const std::string& path);

} // namespace vdb_ewa
