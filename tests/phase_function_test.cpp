/// @file phase_function_test.cpp
/// @brief The Henyey-Greenstein phase function (issue 56's seam) against its closed forms by
///        numerical integration over the sphere: it integrates to 1 (relative to isotropic: to
///        4 pi), its mean cosine is g, g = 0 is isotropic exactly, and its sampling draws cosines
///        distributed as it is.
#include "shading/shading.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace vdb_ewa::detail;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// The integral over the unit sphere of f(cos t) (azimuth integrated: 2 pi), by Simpson's rule
/// in cos t on @a n intervals.
template <typename F>
double overTheSphere(F f, int n = 200000)
{
    const double h = 2.0 / n;
    double sum = f(-1.0) + f(1.0);
    for (int i = 1; i < n; ++i) sum += f(-1.0 + i * h) * (i % 2 ? 4.0 : 2.0);
    return 2.0 * kPi * sum * h / 3.0;
}

} // namespace

TEST(PhaseFunction, IntegratesToOneAndItsMeanCosineIsG)
{
    for (double g : {-0.9, -0.5, -0.1, 0.0, 0.3, 0.6, 0.85}) {
        const double p = overTheSphere([g](double c) { return henyeyGreenstein(c, g) / (4.0 * kPi); });
        const double mean = overTheSphere([g](double c) { return c * henyeyGreenstein(c, g) / (4.0 * kPi); });
        EXPECT_NEAR(p, 1.0, 1e-6) << "g " << g;
        EXPECT_NEAR(mean, g, 1e-6) << "g " << g;
    }
}

TEST(PhaseFunction, IsotropicIsOneExactlyAndForwardScatteringPeaksTowardsTheLight)
{
    for (double c : {-1.0, -0.3, 0.0, 0.7, 1.0}) EXPECT_EQ(henyeyGreenstein(c, 0.0), 1.0);
    const double g = 0.6;
    EXPECT_NEAR(henyeyGreenstein(1.0, g), (1.0 + g) / ((1.0 - g) * (1.0 - g)), 1e-12); // straight through
    EXPECT_NEAR(henyeyGreenstein(-1.0, g), (1.0 - g) / ((1.0 + g) * (1.0 + g)), 1e-12); // straight back
    EXPECT_NEAR(henyeyGreenstein(0.4, g), henyeyGreenstein(-0.4, -g), 1e-12);          // -g mirrors it
}

// Cosines drawn by sampleHenyeyGreenstein fall in each bin of cos t as often as the phase's
// integral over that bin says, and their mean is g.
TEST(PhaseFunction, SamplingDrawsCosinesDistributedAsThePhase)
{
    std::mt19937_64 random(56);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    constexpr int kBins = 20, kSamples = 400000;
    for (double g : {-0.7, 0.0, 0.5, 0.9}) {
        std::vector<int> counts(kBins, 0);
        double mean = 0;
        for (int i = 0; i < kSamples; ++i) {
            const double c = sampleHenyeyGreenstein(g, uniform(random));
            ASSERT_GE(c, -1.0);
            ASSERT_LE(c, 1.0);
            mean += c;
            ++counts[std::min(kBins - 1, int((c + 1.0) / 2.0 * kBins))];
        }
        EXPECT_NEAR(mean / kSamples, g, 0.005) << "g " << g;
        for (int b = 0; b < kBins; ++b) {
            const double lo = -1.0 + 2.0 * b / kBins, hi = lo + 2.0 / kBins;
            const double expected = overTheSphere([&](double c) { return c >= lo && c < hi ? henyeyGreenstein(c, g) / (4.0 * kPi) : 0.0; }, 40000);
            const double observed = double(counts[std::size_t(b)]) / kSamples;
            EXPECT_NEAR(observed, expected, 5.0 * std::sqrt(expected / kSamples) + 2e-4) << "g " << g << " bin " << b;
        }
    }
}
