/// @file footprint_scalar.cpp
/// @brief The scalar inner loop, as the library compiles it (baseline x86-64): row spans of the
///        ellipse, incremental exp (forward differencing in the exponential domain), spread.
#include "footprint_kernels.h"

#include <algorithm>
#include <cmath>

namespace roofline {

std::size_t splatScalar(const std::vector<Footprint>& splats, Accumulators& acc)
{
    std::size_t samples = 0;
    for (const Footprint& s : splats) {
        const float kx = std::exp(-s.qa);
        for (int y = 0; y < kTile; ++y) {
            float dy;
            int x0, x1;
            if (!rowSpan(s, y, dy, x0, x1)) continue;
            const float dx0 = float(x0) + 0.5f - s.cx;
            float g = std::exp(-0.5f * (s.qa * dx0 * dx0 + 2.0f * s.qb * dx0 * dy + s.qc * dy * dy));
            float m = std::exp(-0.5f * (s.qa * (2.0f * dx0 + 1.0f) + 2.0f * s.qb * dy));
            float* tau = acc.tau + y * kTile;
            float* m1 = acc.m1 + y * kTile;
            float* m2 = acc.m2 + y * kTile;
            for (int x = x0; x <= x1; ++x) {
                tau[x] += g * s.tau;
                m1[x] += g * s.w1;
                m2[x] += g * s.w2;
                g *= m;
                m *= kx;
            }
            samples += std::size_t(x1 - x0 + 1);
        }
    }
    return samples;
}

std::size_t compositeScalar(Accumulators& acc)
{
    for (int p = 0; p < kPixels; ++p) {
        const float absorbed = 1.0f - std::exp(-acc.tau[p]);
        acc.colour[p] += acc.transmittance[p] * absorbed * acc.emission[p];
        acc.transmittance[p] *= 1.0f - absorbed;
        acc.tau[p] = 0.0f;
    }
    return kPixels;
}

} // namespace roofline
