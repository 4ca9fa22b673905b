/// @file slab_share_test.cpp
/// @brief Image-aligned slab shares (ewa-brief Sec. 5) against numerical integration.
#include <vdb_ewa/slab_share.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace vdb_ewa;

namespace {

std::vector<float> shares(const SlabGrid& g, double mu, double sd, double lo, double hi, std::int64_t& first)
{
    std::vector<float> out(1024);
    out.resize(std::size_t(slabShares(g, mu, sd, 3.0, lo, hi, first, out.data(), 1024)));
    return out;
}

} // namespace

TEST(SlabShare, SharesOfAnUnclippedKernelSumToOne)
{
    for (double thickness : {0.1, 0.5, 1.0, 3.0}) {
        for (double mu : {0.0, 0.37, 5.5, 1234.56}) {
            const SlabGrid g{0.0, thickness};
            std::int64_t first = 0;
            const std::vector<float> s = shares(g, mu, 0.6, -1e9, 1e9, first);
            double sum = 0.0;
            for (float v : s) sum += v;
            EXPECT_NEAR(sum, 1.0, 1e-5) << "thickness " << thickness << " mu " << mu;
            EXPECT_EQ(first, g.index(mu - 1.8));
        }
    }
}

TEST(SlabShare, EachShareIsTheGaussianMassInItsSlab)
{
    const SlabGrid g{0.25, 0.4};
    const double mu = 2.0, sd = 0.5;
    std::int64_t first = 0;
    const std::vector<float> s = shares(g, mu, sd, -1e9, 1e9, first);
    const double mass = std::erf(3.0 / std::sqrt(2.0)); // truncation at 3 sd
    for (std::size_t i = 0; i < s.size(); ++i) {
        const double z0 = std::max(g.start(first + std::int64_t(i)), mu - 3 * sd);
        const double z1 = std::min(g.start(first + std::int64_t(i) + 1), mu + 3 * sd);
        // Midpoint rule on the Gaussian density.
        double integral = 0.0;
        const int n = 2000;
        for (int k = 0; k < n; ++k) {
            const double z = z0 + (k + 0.5) * (z1 - z0) / n;
            integral += std::exp(-0.5 * (z - mu) * (z - mu) / (sd * sd)) / (sd * std::sqrt(2 * M_PI)) * (z1 - z0) / n;
        }
        EXPECT_NEAR(s[i], integral / mass, 1e-5);
    }
}

TEST(SlabShare, NearPlaneDropsTheHiddenPart)
{
    const SlabGrid g{0.0, 0.5};
    std::int64_t first = 0;
    const std::vector<float> s = shares(g, 1.0, 0.3, 1.0, 1e9, first); // clip at the mean
    double sum = 0.0;
    for (float v : s) sum += v;
    EXPECT_NEAR(sum, 0.5, 1e-5);
    EXPECT_TRUE(shares(g, 1.0, 0.3, 5.0, 1e9, first).empty()); // wholly before the near plane
}

TEST(SlabShare, HomogeneousSlabUpdateIsExact)
{
    // One slab of optical depth tau and uniform source c: C = c (1 - e^-tau), T = e^-tau.
    for (float tau : {1e-9f, 1e-3f, 0.5f, 5.0f, 80.0f}) {
        float c = 0.0f, t = 1.0f;
        compositeSlab(tau, 0.7f * tau, c, t);
        EXPECT_NEAR(t, std::exp(-tau), 1e-6);
        EXPECT_NEAR(c, 0.7 * (1.0 - std::exp(-double(tau))), 1e-6);
    }
    // Splitting a homogeneous segment into two slabs changes nothing.
    float c1 = 0.0f, t1 = 1.0f, c2 = 0.0f, t2 = 1.0f;
    compositeSlab(2.0f, 0.4f * 2.0f, c1, t1);
    compositeSlab(1.0f, 0.4f, c2, t2);
    compositeSlab(1.0f, 0.4f, c2, t2);
    EXPECT_NEAR(c1, c2, 1e-6);
    EXPECT_NEAR(t1, t2, 1e-6);
}

TEST(SlabShare, MomentsAreThoseOfTheGaussianInItsSlab)
{
    // The mean and mean square of the position (in slab thicknesses from the slab's front) of
    // the Gaussian restricted to each slab, against the midpoint rule on the density itself.
    const SlabGrid g{0.25, 0.4};
    for (const double mu : {0.0, 0.37, 1.9}) {
        const double sd = 0.45, clipNear = mu - 0.5, clipFar = 1e9;
        std::int64_t first = 0;
        std::vector<float> s(64), m(128);
        const int n = slabShares(g, mu, sd, 3.0, clipNear, clipFar, first, s.data(), 64, m.data());
        ASSERT_GT(n, 2);
        for (int i = 0; i < n; ++i) {
            const double z0 = std::max(g.start(first + i), clipNear), z1 = std::min(g.start(first + i + 1), mu + 3.0 * sd);
            double w = 0.0, m1 = 0.0, m2 = 0.0;
            const int steps = 20000;
            for (int k = 0; k < steps; ++k) {
                const double z = z0 + (k + 0.5) * (z1 - z0) / steps;
                const double d = std::exp(-0.5 * (z - mu) * (z - mu) / (sd * sd));
                const double u = (z - g.start(first + i)) / g.thickness;
                w += d;
                m1 += d * u;
                m2 += d * u * u;
            }
            EXPECT_NEAR(m[2 * i], m1 / w, 1e-4) << "mu " << mu << " slab " << i;
            EXPECT_NEAR(m[2 * i + 1], m2 / w, 1e-4) << "mu " << mu << " slab " << i;
        }
    }
}

TEST(SlabShare, SlabLightTransmittanceIsTheLayersIntegral)
{
    // A uniform layer of optical depth tau, light falling log-linearly from front to back:
    // compositeSlab(tau, S T_eff) must add what int_0^1 tau S T_L(u) e^(-tau u) du adds
    // (midpoint rule, 20000 steps), from thin to opaque layers and with the light brighter
    // at the back (light from behind the layer).
    for (float tau : {0.0f, 1e-5f, 0.01f, 0.5f, 3.0f, 20.0f})
        for (const auto& [front, back] : {std::pair{1.0f, 1.0f}, {0.9f, 0.2f}, {0.05f, 0.6f}, {1.0f, 1e-3f}}) {
            const int n = 20000;
            double integral = 0.0;
            for (int i = 0; i < n; ++i) {
                const double u = (i + 0.5) / n;
                integral += std::pow(double(front), 1.0 - u) * std::pow(double(back), u) * std::exp(-double(tau) * u);
            }
            integral /= n;                                 // int T_L e^(-tau u) du
            const double meanExp = tau > 0.0f ? -std::expm1(-double(tau)) / tau : 1.0; // int e^(-tau u) du
            const double expected = integral / meanExp;
            EXPECT_NEAR(slabLightTransmittance(tau, front, back), expected, 2e-6 * expected + 1e-9)
                << "tau " << tau << " front " << front << " back " << back;
            // The compositor's form: the integral itself, the light given by its optical depth
            // across the layer, ln(front / back).
            const float logRatio = lightLogRatio(std::log(front), std::log(back));
            EXPECT_NEAR(slabLightIntegral(tau, front, logRatio), integral, 2e-6 * integral + 1e-9)
                << "tau " << tau << " front " << front << " back " << back;
            // compositeSlab adds T x the integrated source and attenuates as the layer does.
            float colour = 0.0f, t = 0.5f;
            compositeSlab(tau, slabAbsorbed(tau), 0.0f, slabLightIntegral(tau, front, logRatio), colour, t);
            if (tau > 0.0f) {
                EXPECT_NEAR(colour, 0.5 * integral, 2e-6 * integral + 1e-9);
                EXPECT_NEAR(t, 0.5 * std::exp(-double(tau)), 1e-7);
            }
        }
}
