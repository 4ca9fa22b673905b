/// @file footprint_avx2.cpp
/// @brief The inner loop 8 pixels a vector (xsimd, AVX2 + FMA; this file alone is compiled with
///        -mavx2 -mfma): r for 8 pixels of a row at once, exp evaluated per lane (no serial
///        forward-differencing chain), spread with FMAs.
#include "footprint_kernels.h"

#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <cmath>

namespace roofline {

using Batch = xsimd::batch<float, xsimd::avx2>;
constexpr int kLanes = int(Batch::size);

std::size_t splatAvx2(const std::vector<Footprint>& splats, Accumulators& acc)
{
    alignas(32) float lane[kLanes];
    for (int i = 0; i < kLanes; ++i) lane[i] = float(i);
    const Batch offsets = Batch::load_aligned(lane);
    std::size_t samples = 0;
    for (const Footprint& s : splats) {
        for (int y = 0; y < kTile; ++y) {
            float dy;
            int x0, x1;
            if (!rowSpan(s, y, dy, x0, x1)) continue;
            // r(dx) = qa dx^2 + (2 qb dy) dx + qc dy^2, 8 pixels a vector; lanes past the span
            // weigh 0 (the tile row is 16 wide: two vectors).
            const Batch a(s.qa), b(2.0f * s.qb * dy), c(s.qc * dy * dy), half2(-0.5f);
            float* tau = acc.tau + y * kTile;
            float* m1 = acc.m1 + y * kTile;
            float* m2 = acc.m2 + y * kTile;
            for (int x = (x0 / kLanes) * kLanes; x <= x1; x += kLanes) {
                const Batch xs = offsets + Batch(float(x));
                const Batch dx = xs + Batch(0.5f - s.cx);
                const Batch r = xsimd::fma(xsimd::fma(a, dx, b), dx, c);
                const auto inside = (xs >= Batch(float(x0))) && (xs <= Batch(float(x1)));
                const Batch g = xsimd::select(inside, xsimd::exp(half2 * r), Batch(0.0f));
                xsimd::fma(g, Batch(s.tau), Batch::load_unaligned(tau + x)).store_unaligned(tau + x);
                xsimd::fma(g, Batch(s.w1), Batch::load_unaligned(m1 + x)).store_unaligned(m1 + x);
                xsimd::fma(g, Batch(s.w2), Batch::load_unaligned(m2 + x)).store_unaligned(m2 + x);
            }
            samples += std::size_t(x1 - x0 + 1);
        }
    }
    return samples;
}

std::size_t compositeAvx2(Accumulators& acc)
{
    for (int p = 0; p < kPixels; p += kLanes) {
        const Batch t = Batch::load_unaligned(acc.transmittance + p);
        const Batch absorbed = Batch(1.0f) - xsimd::exp(-Batch::load_unaligned(acc.tau + p));
        xsimd::fma(t * absorbed, Batch::load_unaligned(acc.emission + p), Batch::load_unaligned(acc.colour + p))
            .store_unaligned(acc.colour + p);
        (t * (Batch(1.0f) - absorbed)).store_unaligned(acc.transmittance + p);
        Batch(0.0f).store_unaligned(acc.tau + p);
    }
    return kPixels;
}

} // namespace roofline
