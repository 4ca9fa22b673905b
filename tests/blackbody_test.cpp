/// @file blackbody_test.cpp
/// @brief The blackbody module against published Planckian-locus chromaticities, against Planck's
///        law integrated here (the Stefan-Boltzmann constant), the Rec.709 matrix against D65
///        white, and its guards at the extremes.
#include "shading/shading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>

using namespace vdb_ewa;
using namespace vdb_ewa::detail;

namespace {

Vec2d chromaticity(const Vec3d& xyz)
{
    const double sum = xyz.x + xyz.y + xyz.z;
    return Vec2d(xyz.x / sum, xyz.y / sum);
}

} // namespace

TEST(Blackbody, PlanckianChromaticityMatchesThePublishedTable)
{
    // CIE 1931 2 degree (x, y) of the Planckian locus, tabulated every 50 K from 1000 K in
    // Radiance's src/cal/cal/blackbody.cal (cct_x, cct_y; github.com/NREL/Radiance), 7 digits.
    // Kim et al.'s cubic-spline fit (Wikipedia "Planckian locus", Approximation) is within 4e-4
    // of them; the CMF table and c2 used here reproduce them to 1e-5.
    struct Point
    {
        double kelvin, x, y;
    };
    for (const Point& p : {Point{1000.0, 0.6527561, 0.3444569}, Point{3000.0, 0.4369393, 0.4040768},
             Point{6500.0, 0.3135299, 0.3236324}}) {
        const Vec3d xyz = blackbodyXyz(p.kelvin);
        EXPECT_DOUBLE_EQ(xyz.y, 1.0) << p.kelvin;
        const Vec2d xy = chromaticity(xyz);
        EXPECT_NEAR(xy.x, p.x, 2e-5) << p.kelvin << " K";
        EXPECT_NEAR(xy.y, p.y, 2e-5) << p.kelvin << " K";
    }
}

TEST(Blackbody, RadianceFollowsStefanBoltzmann)
{
    // Planck's law, CODATA 2018 h, c, k, integrated from 10 nm to 1 mm (trapezoids in
    // log wavelength; the tails beyond hold less than 1e-7 of the total at these temperatures).
    const double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23;
    auto planck = [&](double lambda, double kelvin) {
        return 2.0 * h * c * c / std::pow(lambda, 5) / std::expm1(h * c / (lambda * k * kelvin));
    };
    for (const double kelvin : {1500.0, 6500.0}) {
        const int n = 200000;
        const double a = std::log(10e-9), b = std::log(1e-3), step = (b - a) / n;
        double sum = 0.0;
        for (int i = 0; i <= n; ++i) {
            const double lambda = std::exp(a + step * i);
            sum += (i == 0 || i == n ? 0.5 : 1.0) * planck(lambda, kelvin) * lambda; // d lambda = lambda d ln lambda
        }
        EXPECT_NEAR(blackbodyRadiance(kelvin) / (sum * step), 1.0, 1e-6) << kelvin << " K";
    }
}

TEST(Blackbody, Rec709MatrixMapsD65WhiteToOne)
{
    // D65 white as the matrix's source gives it (Lindbloom: X, Y, Z = 0.95047, 1, 1.08883):
    // R = G = B = 1. A transposed matrix (GLM's constructors take columns) would not give it.
    const Vec3d rgb = xyzToLinearRec709(Vec3d(0.95047, 1.0, 1.08883));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[c], 1.0, 1e-6) << c;
    // Red primary, x, y = 0.64, 0.33: pure R.
    const Vec3d red = xyzToLinearRec709(Vec3d(0.64 / 0.33, 1.0, 0.03 / 0.33));
    EXPECT_NEAR(red.g / red.r, 0.0, 1e-5);
    EXPECT_NEAR(red.b / red.r, 0.0, 1e-5);
}

TEST(Blackbody, GuardsTheExtremes)
{
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    for (const double kelvin : {0.0, -5.0, nan, inf, -inf}) {
        const Vec3d xyz = blackbodyXyz(kelvin);
        EXPECT_EQ(xyz, Vec3d(0.0)) << kelvin;
        EXPECT_EQ(blackbodyRadiance(kelvin), 0.0) << kelvin;
    }
    for (const double kelvin : {std::numeric_limits<double>::denorm_min(), 1e-300, 1e-3, 1.0, 20.0, 1e6, 1e30,
             std::numeric_limits<double>::max()}) {
        const Vec3d xyz = blackbodyXyz(kelvin);
        const Vec3d rgb = xyzToLinearRec709(xyz);
        for (int c = 0; c < 3; ++c) {
            EXPECT_TRUE(std::isfinite(xyz[c]) && xyz[c] >= 0.0) << kelvin << " K, " << c;
            EXPECT_TRUE(std::isfinite(rgb[c])) << kelvin << " K, " << c;
        }
        EXPECT_DOUBLE_EQ(xyz.y, 1.0) << kelvin;
        if (kelvin >= 1e-3 && kelvin <= 1e6) { // sigma T^4 underflows below ~1e-79 K
            EXPECT_TRUE(std::isfinite(blackbodyRadiance(kelvin)) && blackbodyRadiance(kelvin) > 0.0) << kelvin;
        }
    }
    // Cold: all light at the table's longest wavelength, 830 nm (x, y = 0.7347, 0.2653 there).
    const Vec2d cold = chromaticity(blackbodyXyz(1.0));
    EXPECT_NEAR(cold.x, 0.000001251141 / (0.000001251141 + 0.00000045181), 1e-9);
    // Hot: the Rayleigh-Jeans limit (lambda^-4), at 1e6 K already within 1e-3.
    const Vec2d hot = chromaticity(blackbodyXyz(1e6)), limit = chromaticity(blackbodyXyz(1e30));
    EXPECT_NEAR(hot.x, limit.x, 1e-3);
    EXPECT_NEAR(hot.y, limit.y, 1e-3);
    // 1e6 K: sigma T^4 / pi = 1.805e16 W m^-2 sr^-1.
    EXPECT_NEAR(blackbodyRadiance(1e6) / 1.80494e16, 1.0, 1e-4);
}
