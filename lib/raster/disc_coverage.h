/// @file disc_coverage.h
/// @brief A surface kernel's disc seen through the camera: which parts of a pixel it covers
///        (visibility splatting, Zwicker et al. 2001 Sec. 5; docs/equations.md#surface-coverage).
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/types.h>

#include <cstdint>

namespace vdb_ewa {
namespace detail {

/// Coverage is sampled at 4x4 stratified points per pixel, one bit each.
constexpr int kSubsamplesPerAxis = 4;
constexpr int kSubsamples = kSubsamplesPerAxis * kSubsamplesPerAxis;
constexpr std::uint16_t kAllSubsamples = 0xffff;
static_assert(kSubsamples == 16, "one bit per subsample in a 16-bit mask");

/// The disc |q - centre| <= radius of a tangent plane, cut by up to three lines
/// clipDirection . (q - centre) <= clipDistance, where the ray through raster point (x, y)
/// meets the plane at q. The plane seen through a perspective or orthographic camera is a
/// projective map of the raster: q - centre = v / w with v = V h, w = W . h, h = (x, y, 1)
/// (w > 0 for points in front of the eye), so each test is a few multiply-adds.
struct DiscCoverage
{
    double V[3][3];
    double W[3];
    double radius2;
    Vec3d clipDirection[3];
    double clipDistance[3];
    int clipCount = 0;
    double box[4]; ///< raster x0, y0, x1, y1 holding the disc's image (conservative)

    /// Where the ray through raster point (@a x, @a y) meets the disc's plane, as q - centre
    /// (camera space); false behind the eye or where the ray runs along the plane.
    bool planeOffset(double x, double y, Vec3d& offset) const;
    /// Whether the plane point q - centre = @a v / @a w lies on the kept side of every clip
    /// line (at any distance): past a crease a kernel's filtered footprint does not shade the
    /// other face.
    bool keptSide(const Vec3d& v, double w = 1.0) const;
    /// Whether the ray through raster point (@a x, @a y) meets the (clipped) disc.
    bool covers(double x, double y) const;
    /// The subsamples of the pixel centred at (@a px, @a py) whose rays meet the disc.
    std::uint16_t mask(double px, double py) const;

private:
    /// v = V h and w = W . h for h = (x, y, 1).
    void homogeneous(double x, double y, Vec3d& v, double& w) const;
};

/// The disc of @a radius around camera-space @a centre in the plane of unit @a normal, clipped
/// by @a clipCount lines (camera-space unit directions in the plane, distances from the centre).
DiscCoverage discCoverage(const Vec3d& centre, const Vec3d& normal, double radius, const Vec3d* clipDirections,
    const double* clipDistances, int clipCount, const Camera& camera);

} // namespace detail
} // namespace vdb_ewa
