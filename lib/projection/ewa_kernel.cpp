/// @file ewa_kernel.cpp
/// @brief Zwicker et al. 2002, Eq. (26)-(33); see docs/equations.md.
#include <vdb_ewa/ewa_kernel.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {

double Sym2::minEigen() const
{
    const double mean = 0.5 * (xx + yy);
    const double diff = 0.5 * (xx - yy);
    return mean - std::sqrt(diff * diff + xy * xy);
}

Vec3d rayFromCamera(const Vec3d& t)
{
    return {t.x / t.z, t.y / t.z, glm::length(t)};
}

Mat3d rayJacobian(const Vec3d& t)
{
    const double l = glm::length(t);
    const double invZ = 1.0 / t.z;
    const double invZ2 = invZ * invZ;
    return mat3FromRows(
        {invZ, 0.0, -t.x * invZ2},
        {0.0, invZ, -t.y * invZ2},
        {t.x / l, t.y / l, t.z / l});
}

namespace {

/// Where J is formed for a kernel of camera-space centre @a tCentre and size @a size (world):
/// the centre, its direction clamped to 1.3x the frustum edge, and no nearer the eye than
/// params.minDistanceSigmas sizes (docs/numerics.md). Sets the clamp flags of @a fp.
Vec3d jacobianPoint(const Vec3d& tCentre, double size, const ProjectionParams& params, Footprint& fp)
{
    Vec3d tJ = tCentre;
    const double tanX = tCentre.x / tCentre.z, tanY = tCentre.y / tCentre.z;
    if (std::abs(tanX) > params.maxTanX || std::abs(tanY) > params.maxTanY) {
        tJ.x = std::clamp(tanX, -params.maxTanX, params.maxTanX) * tCentre.z;
        tJ.y = std::clamp(tanY, -params.maxTanY, params.maxTanY) * tCentre.z;
        fp.clampedGrazing = true;
    }
    const double minDistance = params.minDistanceSigmas * size;
    const double distance = glm::length(tJ);
    if (distance < minDistance) {
        tJ *= minDistance / distance;
        fp.clampedNear = true;
    }
    return tJ;
}

/// Depth of field: @a cov convolved with the circle of confusion at camera depth @a depth, the
/// lens's covariance scaled by (focalPixels |1/z - 1/focus|)^2: a whole lens, a uniform disc of
/// radius R, gives (R/2)^2 I (ProjectionParams::lens).
Sym2 withConfusion(Sym2 cov, double depth, const ProjectionParams& params)
{
    if (!(params.lens.xx > 0.0 || params.lens.yy > 0.0) || !params.perspective) return cov;
    const double k = params.focalPixels * std::abs(1.0 / depth - 1.0 / params.focusDepth), k2 = k * k;
    cov.xx += k2 * params.lens.xx;
    cov.xy += k2 * params.lens.xy;
    cov.yy += k2 * params.lens.yy;
    return cov;
}

/// Low-pass filter (Eq. 33), conic, peak = @a scale / (2 pi sqrt(det Cov)) (renormalised to the
/// mass inside the cut-off), cut-off box: the steps shared by volume and surface kernels.
void finishFootprint(Sym2 cov, double scale, const ProjectionParams& params, Footprint& fp)
{
    switch (params.antiAliasing) {
    case AntiAliasing::Ewa: // convolution adds covariances
        cov.xx += params.lowpass;
        cov.yy += params.lowpass;
        break;
    case AntiAliasing::Floor: {
        // Raise each principal variance below the low-pass variance to it: footprints wider
        // than a pixel are left exact (the field is already band-limited on the pixel grid),
        // minified ones get EWA's filter size. cov += (lowpass - lambda) v v^T per short axis.
        const double mean = 0.5 * (cov.xx + cov.yy);
        const double half = std::sqrt(0.25 * (cov.xx - cov.yy) * (cov.xx - cov.yy) + cov.xy * cov.xy);
        const double lambdaMin = mean - half, lambdaMax = mean + half;
        if (lambdaMax <= params.lowpass) {
            cov = {params.lowpass, 0.0, params.lowpass};
        } else if (lambdaMin < params.lowpass) {
            // Unit eigenvector of lambdaMin: the larger-normed of the two null-space candidates.
            double vx = cov.xy, vy = lambdaMin - cov.xx;
            const double ux = lambdaMin - cov.yy, uy = cov.xy;
            if (ux * ux + uy * uy > vx * vx + vy * vy) { vx = ux; vy = uy; }
            const double n2 = vx * vx + vy * vy;
            const double add = (params.lowpass - lambdaMin) / n2;
            cov.xx += add * vx * vx;
            cov.xy += add * vx * vy;
            cov.yy += add * vy * vy;
        }
        break;
    }
    case AntiAliasing::Swan: {
        // Uniform scaling: grow the whole footprint until its minor axis has the low-pass
        // variance added; isotropic footprints match EWA, elongated ones over-blur.
        const double lambda = std::max(cov.minEigen(), 1e-12);
        const double s = (lambda + params.lowpass) / lambda;
        cov.xx *= s;
        cov.xy *= s;
        cov.yy *= s;
        break;
    }
    case AntiAliasing::None: {
        // Keep the conic finite for degenerate footprints (a 1e-6 pixel^2 floor).
        cov.xx += 1e-6;
        cov.yy += 1e-6;
        break;
    }
    }
    const double detCov = cov.det();
    if (!(detCov > 0.0) || !std::isfinite(detCov)) return;
    fp.covariance = cov;
    fp.conic = cov.inverse();
    const double c2 = params.cutoffRadius * params.cutoffRadius;
    // Mass of the footprint inside the cut-off, as a share of the whole Gaussian's: 1 - e, or,
    // tapered (the Gaussian less e = exp(-c^2/2)), 1 - e - e c^2/2.
    const double truncated = -std::expm1(-0.5 * c2);
    const double keptMass = !params.renormalize ? 1.0 : params.taper ? truncated - 0.5 * c2 * std::exp(-0.5 * c2) : truncated;
    const double twoPi = 6.283185307179586476925;
    fp.peak = scale / (twoPi * std::sqrt(detCov) * keptMass);
    fp.halfExtent = {std::sqrt(c2 * cov.xx), std::sqrt(c2 * cov.yy)};
    fp.valid = std::isfinite(fp.peak) && std::isfinite(fp.centre.x) && std::isfinite(fp.centre.y);
}

} // namespace

Footprint projectKernel(const Vec3d& tCentre, const Mat3d& covCamera, const ProjectionParams& params)
{
    Footprint fp;
    const double f = params.focalPixels;

    // Ray-space covariance V' = J V J^T (Eq. 31) and |J| (Eq. 32).
    Mat3d covRay;
    double detJ = 1.0;
    if (params.perspective) {
        if (!(tCentre.z > 0.0)) return fp;
        const double size = std::sqrt(covCamera[0][0] + covCamera[1][1] + covCamera[2][2]);
        const Vec3d tJ = jacobianPoint(tCentre, size, params, fp);
        const Mat3d J = rayJacobian(tJ);
        covRay = J * covCamera * glm::transpose(J);
        detJ = glm::length(tJ) / (tJ.z * tJ.z * tJ.z);
        fp.centre = params.principalPoint + f * Vec2d(tCentre.x / tCentre.z, tCentre.y / tCentre.z);
        fp.depth = glm::length(tCentre);
    } else {
        covRay = covCamera; // orthographic: the ray map is the identity, |J| = 1
        fp.centre = params.principalPoint + f * Vec2d(tCentre.x, tCentre.y);
        fp.depth = tCentre.z;
    }

    // Footprint covariance in pixels, S V'_2x2 S^T (Eq. 32, 33). GLM indexes [column][row].
    const Sym2 cov{f * f * covRay[0][0], f * f * covRay[1][0], f * f * covRay[1][1]};
    const Sym2 covPlane{covRay[0][0], covRay[1][0], covRay[1][1]};

    // Depth spread along the ray through the centre: Var(x2 | x0, x1).
    {
        const double d = covPlane.det();
        const double v0 = covRay[2][0], v1 = covRay[2][1];
        double condVar = covRay[2][2];
        if (d > 0.0) condVar -= (covPlane.yy * v0 * v0 - 2.0 * covPlane.xy * v0 * v1 + covPlane.xx * v1 * v1) / d;
        fp.depthSd = std::sqrt(std::max(condVar, 1e-6 * covRay[2][2]));
    }
    finishFootprint(withConfusion(cov, tCentre.z, params), detJ * f * f, params, fp);
    return fp;
}

Footprint projectSurfaceKernel(const Vec3d& tCentre, const Vec3d& tangent0, const Vec3d& tangent1, double sigma,
    const ProjectionParams& params)
{
    Footprint fp;
    const double f = params.focalPixels;
    // Screen Jacobian of the projection at the centre (rows: d raster / d t), pixels per world
    // unit: the 2x2 J of Eq. 34 composed with the viewport scale.
    Vec3d row0, row1;
    if (params.perspective) {
        if (!(tCentre.z > 0.0)) return fp;
        const Vec3d tJ = jacobianPoint(tCentre, sigma, params, fp);
        const double invZ = 1.0 / tJ.z;
        row0 = f * Vec3d(invZ, 0.0, -tJ.x * invZ * invZ);
        row1 = f * Vec3d(0.0, invZ, -tJ.y * invZ * invZ);
        fp.centre = params.principalPoint + f * Vec2d(tCentre.x / tCentre.z, tCentre.y / tCentre.z);
        fp.depth = glm::length(tCentre);
    } else {
        row0 = Vec3d(f, 0.0, 0.0);
        row1 = Vec3d(0.0, f, 0.0);
        fp.centre = params.principalPoint + f * Vec2d(tCentre.x, tCentre.y);
        fp.depth = tCentre.z;
    }
    // M = J S_k (Eq. 35): tangent-plane units -> pixels; V'_k = sigma^2 M M^T.
    const double m00 = glm::dot(row0, tangent0), m01 = glm::dot(row0, tangent1);
    const double m10 = glm::dot(row1, tangent0), m11 = glm::dot(row1, tangent1);
    const double s2 = sigma * sigma;
    const Sym2 cov{s2 * (m00 * m00 + m01 * m01), s2 * (m00 * m10 + m01 * m11), s2 * (m10 * m10 + m11 * m11)};
    fp.depthSd = 0.0;
    // rho(x) = |det M| G_{cov}(x - centre): per unit of surface area (Heckbert's EWA filter).
    // No circle of confusion: a surface's coverage comes from its discs (disc_coverage.h), which
    // the lens does not blur; level sets and --iso surfaces render in focus.
    finishFootprint(cov, std::abs(m00 * m11 - m01 * m10), params, fp);
    return fp;
}

} // namespace vdb_ewa
