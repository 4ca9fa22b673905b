/// @file ewa_kernel_test.cpp
/// @brief Zwicker et al. 2002, Eq. (26), (29), (31)-(33) against finite differences and
///        numerical integration along exact perspective rays.
#include <vdb_ewa/ewa_kernel.h>

#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <random>

using namespace vdb_ewa;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Unit-integral 3D Gaussian of covariance V at offset d.
double gauss3(const Mat3d& V, const Vec3d& d)
{
    const Mat3d inv = glm::inverse(V);
    const double r = glm::dot(d, inv * d);
    return std::exp(-0.5 * r) / std::sqrt(std::pow(2.0 * kPi, 3) * glm::determinant(V));
}

/// Exact footprint: integral of G_V(t - tk) along the ray through plane point (x0, x1),
/// parameterised by distance s from the eye (Eq. 11), by Simpson's rule.
double rayIntegral(const Mat3d& V, const Vec3d& tk, double x0, double x1)
{
    const Vec3d dir = glm::normalize(Vec3d(x0, x1, 1.0));
    const double l = glm::length(tk), sd = std::sqrt(std::max({V[0][0], V[1][1], V[2][2]}));
    const double a = l - 10.0 * sd, b = l + 10.0 * sd;
    const int n = 4000;
    const double h = (b - a) / n;
    double sum = 0.0;
    for (int i = 0; i <= n; ++i) {
        const double s = a + i * h;
        const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * gauss3(V, s * dir - tk);
    }
    return sum * h / 3.0;
}

Mat3d anisotropicCovariance(double sigma)
{
    // An ellipsoid with axes sigma * (1, 0.5, 2) rotated off the camera axes.
    const Mat3d R = glm::mat3_cast(glm::angleAxis(0.7, glm::normalize(Vec3d(0.3, 1.0, 0.2))));
    const Mat3d S(Vec3d(sigma, 0, 0), Vec3d(0, 0.5 * sigma, 0), Vec3d(0, 0, 2.0 * sigma));
    return R * S * S * glm::transpose(R);
}

/// Relative L1 error of the affine footprint (Eq. 32) against the exact ray integral, over
/// plane points within 2.5 footprint standard deviations of the centre.
double footprintError(const Vec3d& tk, const Mat3d& V)
{
    // In pixels the footprint is |J| f^2 G2_{f^2 V'}(p) = |J| G2_{V'}(x): the same numbers as
    // in plane units x = (p - principal) / f. A large f keeps --aa none's 1e-6 px^2 floor negligible.
    ProjectionParams p;
    p.focalPixels = 1.0e4;
    p.principalPoint = Vec2d(0.0);
    p.antiAliasing = AntiAliasing::None;
    p.cutoffRadius = 6.0; // keptMass ~ 1
    const Footprint fp = projectKernel(tk, V, p);
    EXPECT_TRUE(fp.valid);
    const double sx = std::sqrt(fp.covariance.xx), sy = std::sqrt(fp.covariance.yy);
    double err = 0.0, norm = 0.0;
    for (int i = -6; i <= 6; ++i)
        for (int j = -6; j <= 6; ++j) {
            const Vec2d x = fp.centre + Vec2d(i * sx, j * sy) * (2.5 / 6.0);
            const Vec2d d = x - fp.centre;
            const double approx = fp.peak * std::exp(-0.5 * fp.conic.quad(d.x, d.y));
            const double exact = rayIntegral(V, tk, x.x / p.focalPixels, x.y / p.focalPixels);
            err += std::abs(approx - exact);
            norm += exact;
        }
    return err / norm;
}

} // namespace

TEST(EwaKernel, JacobianMatchesFiniteDifferencesOfEq26)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-3.0, 3.0), z(0.2, 10.0);
    for (int n = 0; n < 50; ++n) {
        const Vec3d t(u(rng), u(rng), z(rng));
        const Mat3d J = rayJacobian(t);
        for (int c = 0; c < 3; ++c) {
            Vec3d e(0.0);
            e[c] = 1e-6 * std::max(1.0, std::abs(t[c]));
            const Vec3d fd = (rayFromCamera(t + e) - rayFromCamera(t - e)) / (2.0 * e[c]);
            for (int r = 0; r < 3; ++r) {
                EXPECT_NEAR(J[c][r], fd[r], 1e-6 * std::max(1.0, std::abs(fd[r]))) << "row " << r << " col " << c;
            }
        }
        EXPECT_NEAR(glm::determinant(J), glm::length(t) / (t.z * t.z * t.z), 1e-9 * std::abs(glm::determinant(J)));
    }
}

TEST(EwaKernel, FootprintMatchesRayIntegralOnAxis)
{
    // sigma up to 0.2 at distance 20: the affine map is off by about sigma / distance.
    const Mat3d V = anisotropicCovariance(0.1);
    EXPECT_LT(footprintError(Vec3d(0.0, 0.0, 20.0), V), 0.01);
}

TEST(EwaKernel, FootprintErrorShrinksAsTheLocalAffineApproximationPredicts)
{
    // Off-axis kernel (about 25 degrees): the affine map's error is O(sigma / distance).
    const Mat3d V = anisotropicCovariance(0.1);
    const Vec3d dir = glm::normalize(Vec3d(0.35, 0.3, 1.0));
    double previous = 0.0;
    for (double l : {2.0, 4.0, 8.0, 16.0, 32.0, 64.0}) {
        const double err = footprintError(l * dir, V);
        std::printf("footprint: distance %.0f, sigma/distance %.4f, relative L1 error %.3e\n", l, 0.1 / l, err);
        if (previous > 0.0) {
            EXPECT_GT(previous / err, 1.8) << "error did not halve from distance " << l / 2 << " to " << l;
        }
        previous = err;
    }
    EXPECT_LT(previous, 0.005);
}

TEST(EwaKernel, ConicIsInverseOfFootprint)
{
    ProjectionParams p;
    p.focalPixels = 800.0;
    p.principalPoint = Vec2d(320, 240);
    const Footprint fp = projectKernel(Vec3d(0.3, -0.2, 5.0), anisotropicCovariance(0.02), p);
    ASSERT_TRUE(fp.valid);
    const Sym2& c = fp.covariance;
    const Sym2& q = fp.conic;
    EXPECT_NEAR(c.xx * q.xx + c.xy * q.xy, 1.0, 1e-12);
    EXPECT_NEAR(c.xx * q.xy + c.xy * q.yy, 0.0, 1e-12);
    EXPECT_NEAR(c.xy * q.xy + c.yy * q.yy, 1.0, 1e-12);
}

TEST(EwaKernel, LowpassAddsItsVarianceAndKeepsTheIntegral)
{
    ProjectionParams p;
    p.focalPixels = 500.0;
    p.cutoffRadius = 6.0;
    const Vec3d t(0.1, 0.05, 10.0);
    const Mat3d V = anisotropicCovariance(0.01);
    p.antiAliasing = AntiAliasing::None;
    const Footprint raw = projectKernel(t, V, p);
    p.antiAliasing = AntiAliasing::Ewa;
    p.lowpass = 1.0;
    const Footprint filtered = projectKernel(t, V, p);
    EXPECT_NEAR(filtered.covariance.xx - raw.covariance.xx, 1.0, 1e-5);
    EXPECT_NEAR(filtered.covariance.yy - raw.covariance.yy, 1.0, 1e-5);
    EXPECT_NEAR(filtered.covariance.xy, raw.covariance.xy, 1e-9);
    // Integral of peak * exp(-r/2) over the plane = peak * 2 pi sqrt(det): unchanged by Eq. 22.
    const double twoPi = 2.0 * kPi;
    EXPECT_NEAR(filtered.peak * twoPi * std::sqrt(filtered.covariance.det()),
        raw.peak * twoPi * std::sqrt(raw.covariance.det()), 1e-9 * raw.peak * twoPi * std::sqrt(raw.covariance.det()));
}

TEST(EwaKernel, SubPixelFootprintIsDominatedByTheLowpass)
{
    ProjectionParams p;
    p.focalPixels = 100.0;
    p.lowpass = 1.0;
    const Footprint fp = projectKernel(Vec3d(0, 0, 1000.0), Mat3d(1e-4), p); // sigma 0.01 at 1000
    ASSERT_TRUE(fp.valid);
    EXPECT_NEAR(fp.covariance.xx, 1.0, 1e-6);
    EXPECT_NEAR(fp.covariance.yy, 1.0, 1e-6);
}

TEST(EwaKernel, SwanScalingMatchesEwaWhenIsotropicAndOverBlursWhenElongated)
{
    ProjectionParams p;
    p.focalPixels = 400.0;
    const Vec3d t(0, 0, 10.0);
    p.antiAliasing = AntiAliasing::Ewa;
    const Footprint ewaIso = projectKernel(t, Mat3d(1e-3), p);
    p.antiAliasing = AntiAliasing::Swan;
    const Footprint swanIso = projectKernel(t, Mat3d(1e-3), p);
    EXPECT_NEAR(swanIso.covariance.xx, ewaIso.covariance.xx, 1e-9);
    EXPECT_NEAR(swanIso.covariance.yy, ewaIso.covariance.yy, 1e-9);

    Mat3d elongated(1e-3);
    elongated[0][0] = 1e-1; // long along x
    p.antiAliasing = AntiAliasing::Ewa;
    const Footprint ewa = projectKernel(t, elongated, p);
    p.antiAliasing = AntiAliasing::Swan;
    const Footprint swan = projectKernel(t, elongated, p);
    EXPECT_NEAR(swan.covariance.yy, ewa.covariance.yy, 1e-9); // minor axis identical
    EXPECT_GT(swan.covariance.xx, 1.5 * ewa.covariance.xx);  // major axis blurred further
}

TEST(EwaKernel, KernelBehindTheEyeIsInvalid)
{
    ProjectionParams p;
    EXPECT_FALSE(projectKernel(Vec3d(0, 0, -1.0), Mat3d(1.0), p).valid);
    EXPECT_FALSE(projectKernel(Vec3d(0, 0, 0.0), Mat3d(1.0), p).valid);
}

TEST(EwaKernel, FlattenedVolumeKernelConvergesToTheSurfaceKernel)
{
    // Eq. 37: a volume kernel flattened along its normal by 1/s tends, as s grows, to the
    // surface kernel of the same tangential variance: the same screen covariance, and a ray
    // integral through the centre equal to the surface density divided by |cos| of the angle
    // between the ray and the normal (a tilted sheet is crossed obliquely).
    ProjectionParams p;
    p.focalPixels = 800.0;
    p.principalPoint = {320.0, 240.0};
    p.lowpass = 1e-9; // compare the footprints themselves
    const Vec3d t(0.6, -0.3, 5.0);
    const Vec3d normal = glm::normalize(Vec3d(0.3, 0.5, -0.8));
    const Vec3d tangent0 = glm::normalize(glm::cross(normal, Vec3d(1, 0, 0)));
    const Vec3d tangent1 = glm::cross(normal, tangent0);
    const double sigma = 0.05;
    const Footprint surface = projectSurfaceKernel(t, tangent0, tangent1, sigma, p);
    ASSERT_TRUE(surface.valid);
    const double cosine = std::abs(glm::dot(normal, glm::normalize(t)));
    double previous = 1e300;
    for (const double s : {2.0, 8.0, 32.0, 128.0, 512.0}) {
        const Mat3d cov = sigma * sigma * (glm::outerProduct(tangent0, tangent0) + glm::outerProduct(tangent1, tangent1)) +
                          (sigma / s) * (sigma / s) * glm::outerProduct(normal, normal);
        const Footprint volume = projectKernel(t, cov, p);
        ASSERT_TRUE(volume.valid);
        const double error = std::max({std::abs(volume.covariance.xx - surface.covariance.xx),
                                 std::abs(volume.covariance.xy - surface.covariance.xy),
                                 std::abs(volume.covariance.yy - surface.covariance.yy)}) /
                             surface.covariance.xx;
        EXPECT_LT(error, previous / 10.0) << "s = " << s << ": the error falls as 1/s^2";
        previous = error;
        if (s == 512.0) {
            EXPECT_LT(error, 1e-5);
            EXPECT_NEAR(volume.peak * cosine, surface.peak, 1e-3 * surface.peak);
        }
    }
    // With the surface in the image plane the footprint is the tangent Gaussian scaled by f/z.
    const Footprint facing = projectSurfaceKernel(Vec3d(0, 0, 5), Vec3d(1, 0, 0), Vec3d(0, 1, 0), sigma, p);
    EXPECT_NEAR(facing.covariance.xx, std::pow(sigma * 800.0 / 5.0, 2), 1e-6);
    EXPECT_NEAR(facing.covariance.xy, 0.0, 1e-9);
    EXPECT_NEAR(facing.peak, 1.0 / (2.0 * 3.14159265358979 * sigma * sigma) / -std::expm1(-4.5), 1e-3);
}

TEST(EwaKernel, SurfaceFootprintMatchesFiniteDifferencesOfTheProjection)
{
    // The screen covariance sigma^2 M M^T against M from finite differences of the pinhole map.
    ProjectionParams p;
    p.focalPixels = 500.0;
    p.principalPoint = {0.0, 0.0};
    p.lowpass = 1e-9;
    const Vec3d t(-1.2, 0.7, 4.0);
    const Vec3d a = glm::normalize(Vec3d(1.0, 0.2, 0.4)), b = glm::normalize(glm::cross(a, Vec3d(0.1, 1.0, 0.3)));
    auto raster = [&](const Vec3d& q) { return Vec2d(500.0 * q.x / q.z, 500.0 * q.y / q.z); };
    const double h = 1e-5;
    const Vec2d d0 = (raster(t + h * a) - raster(t - h * a)) / (2.0 * h);
    const Vec2d d1 = (raster(t + h * b) - raster(t - h * b)) / (2.0 * h);
    const double sigma = 0.1;
    const Footprint fp = projectSurfaceKernel(t, a, b, sigma, p);
    EXPECT_NEAR(fp.covariance.xx, sigma * sigma * (d0.x * d0.x + d1.x * d1.x), 1e-4);
    EXPECT_NEAR(fp.covariance.xy, sigma * sigma * (d0.x * d0.y + d1.x * d1.y), 1e-4);
    EXPECT_NEAR(fp.covariance.yy, sigma * sigma * (d0.y * d0.y + d1.y * d1.y), 1e-4);
    EXPECT_NEAR(fp.centre.x, raster(t).x, 1e-9);
}
