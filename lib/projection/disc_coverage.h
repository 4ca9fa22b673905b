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
/// projective map of the raster: q - centre = v / w with v = V h, w = W . h, h = (x - ox,
/// y - oy, 1) around the centre's raster point (ox, oy), w > 0 in front of the eye. So the disc
/// is a conic of the raster, h^T (V^T V - radius^2 W W^T) h <= 0, and each clip a half-plane,
/// (V^T clipDirection - clipDistance W) . h <= 0: each test is a few multiply-adds.
struct DiscCoverage
{
    double ox = 0, oy = 0;  ///< raster origin of h
    double conic[6] = {};   ///< a x^2 + b xy + c y^2 + d x + e y + f <= 0 inside the disc (local x, y)
    double W[3] = {};       ///< w = W . h
    double Z[3] = {};       ///< camera depth of q - centre, times w: V's third row
    double clip[3][3] = {}; ///< clip . h <= 0 on the kept side of each line
    int clipCount = 0;
    double box[4] = {};     ///< raster x0, y0, x1, y1 holding the disc's image (conservative)

    /// The camera depth of q - centre where the ray through raster point (@a x, @a y) meets
    /// the disc's plane; false behind the eye or where the ray runs along the plane.
    bool depthOffset(double x, double y, double& dz) const;
    /// Whether the plane point seen at raster (@a x, @a y) lies on the kept side of every clip
    /// line (at any distance; the point must lie in front of the eye): past a crease a kernel's
    /// filtered footprint does not shade the other face.
    bool keptSide(double x, double y) const;
    /// Whether the ray through raster point (@a x, @a y) meets the (clipped) disc.
    bool covers(double x, double y) const;
    /// The subsamples of the pixel centred at (@a px, @a py) whose rays meet the disc.
    std::uint16_t mask(double px, double py) const;

private:
    // The tests at local (x, y) = raster - (ox, oy).
    bool keptSideLocal(double x, double y) const
    {
        for (int c = 0; c < clipCount; ++c) {
            if (clip[c][0] * x + clip[c][1] * y + clip[c][2] > 0.0) return false;
        }
        return true;
    }
    bool coversLocal(double x, double y) const
    {
        return W[0] * x + W[1] * y + W[2] > 0.0 &&
            conic[0] * x * x + conic[1] * x * y + conic[2] * y * y + conic[3] * x + conic[4] * y + conic[5] <= 0.0 &&
            keptSideLocal(x, y);
    }
};

/// The disc of @a radius around camera-space @a centre in the plane of unit @a normal, clipped
/// by @a clipCount lines (camera-space unit directions in the plane, distances from the centre).
DiscCoverage discCoverage(const Vec3d& centre, const Vec3d& normal, double radius, const Vec3d* clipDirections,
    const double* clipDistances, int clipCount, const Camera& camera);

} // namespace detail
} // namespace vdb_ewa
