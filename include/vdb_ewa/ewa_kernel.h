/// @file ewa_kernel.h
/// @brief The EWA resampling filter of one reconstruction kernel: ray-space projection
///        (Zwicker et al. 2002, Eq. 26, 29, 31), footprint (Eq. 32), low-pass convolution and
///        viewport scaling (Eq. 33), conic and cut-off box (Sec. 7.1).
/// @note Pure math on doubles; see docs/equations.md.
#pragma once

#include "render_settings.h"
#include "types.h"

namespace vdb_ewa {

/// Symmetric 2x2 matrix [xx xy; xy yy].
struct VDB_EWA_API Sym2
{
    double xx = 0, xy = 0, yy = 0;
    double det() const { return xx * yy - xy * xy; }
    Sym2 inverse() const
    {
        const double d = det();
        return {yy / d, -xy / d, xx / d};
    }
    /// Quadratic form d^T M d.
    double quad(double dx, double dy) const { return xx * dx * dx + 2.0 * xy * dx * dy + yy * dy * dy; }
    /// Smaller eigenvalue.
    double minEigen() const;
};

/// Zwicker et al. 2002, Eq. (26): camera space t -> ray space x = (t0/t2, t1/t2, |t|).
VDB_EWA_API Vec3d rayFromCamera(const Vec3d& t);

/// Zwicker et al. 2002, Eq. (29): Jacobian of Eq. (26) at t (rows: d x_i / d t).
/// det = |t| / t2^3.
VDB_EWA_API Mat3d rayJacobian(const Vec3d& t);

/// Everything projectKernel needs to know about the camera and the filter.
struct ProjectionParams
{
    bool perspective = true;
    double focalPixels = 1.0;    ///< viewport scale S = diag(f, f), pixels per plane unit
    Vec2d principalPoint{0, 0};  ///< raster position of the optical axis, pixels
    /// Perspective only: |t0/t2|, |t1/t2| are clamped to these when forming J, so kernels far
    /// outside the frustum edge do not get unbounded footprints (1.3 x the half-frame, gsplat).
    double maxTanX = 1e300, maxTanY = 1e300;
    /// Perspective only: J is formed no closer to the eye than this many kernel standard
    /// deviations (sqrt of the covariance trace), keeping the centre's direction. The peak
    /// optical depth (the column through the centre) does not depend on the distance; only
    /// the angular spread is bounded. See docs/numerics.md.
    double minDistanceSigmas = 3.0;
    AntiAliasing antiAliasing = AntiAliasing::Floor;
    double lowpass = 1.0;        ///< V^h = lowpass * I, pixels^2
    double cutoffRadius = 3.0;   ///< in standard deviations of the filtered footprint
    bool renormalize = true;     ///< divide the peak by the mass kept inside the cut-off
    bool taper = false;          ///< the footprint is the Gaussian less its value at the cut-off (SplatOptions::taper)
    /// Depth of field (perspective): the lens's covariance in its plane (camera t0, t1; world
    /// units^2; zero: a pinhole; Camera::lensCovariance) and the depth in focus. A kernel at
    /// depth z gains its circle of confusion's covariance, (focalPixels |1/z - 1/focusDepth|)^2
    /// times it: (R / 2)^2 I for a whole lens of radius L, R = focalPixels L |1/z -
    /// 1/focusDepth| pixels (a uniform disc of radius R), before the low-pass filter
    /// (docs/equations.md#depth-of-field).
    Sym2 lens{};
    double focusDepth = 1.0;
};

/// A kernel's screen-space resampling filter rho(p) = peak * exp(-0.5 d^T Q d), d = p - centre.
struct Footprint
{
    Vec2d centre;        ///< raster position, pixels
    Sym2 covariance;     ///< S V'_2x2 S^T + V^h, pixels^2 (Eq. 33)
    Sym2 conic;          ///< Q = covariance^-1
    /// Footprint value at the centre for a unit-weight kernel: |J| f^2 / (2 pi sqrt(det Cov)),
    /// divided by the mass kept inside the cut-off (1 - exp(-c^2/2)) when renormalising,
    /// in 1/world-length^2.
    double peak = 0;
    Vec2d halfExtent;    ///< half size of the box of the ellipse d^T Q d = cutoffRadius^2, pixels
    double depth = 0;    ///< kernel centre along its viewing ray (x2 of Eq. 26; t2 if ortho)
    double depthSd = 0;  ///< std. deviation along the viewing ray (conditional on x0, x1)
    bool valid = false;  ///< false if the centre is not in front of the eye
    bool clampedGrazing = false; ///< J formed at a direction clamped to the frustum edge
    bool clampedNear = false;    ///< J formed farther from the eye than the centre lies
};

/// Project a kernel of camera-space centre @a tCentre and camera-space covariance
/// @a covCamera (world units^2) to its screen-space resampling filter (Eq. 31-33).
VDB_EWA_API Footprint projectKernel(const Vec3d& tCentre, const Mat3d& covCamera, const ProjectionParams& params);

/// Project a surface kernel (Sec. 6.3, 6.4): a 2D Gaussian of std. deviation @a sigma (world)
/// in the plane through @a tCentre spanned by the orthonormal camera-space tangents
/// @a tangent0, @a tangent1, the limit of a volume kernel flattened along the normal (Eq. 37).
/// Screen filter (Eq. 35): covariance sigma^2 M M^T + V^h with M = J S_k, J the screen
/// Jacobian at the centre; peak |det M| / (2 pi sqrt(det Cov)) per unit surface area
/// (1/world^2), so that rho = |det M| G_Cov. depthSd is 0.
VDB_EWA_API Footprint projectSurfaceKernel(const Vec3d& tCentre, const Vec3d& tangent0, const Vec3d& tangent1, double sigma,
    const ProjectionParams& params);

} // namespace vdb_ewa
