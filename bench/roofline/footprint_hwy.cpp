/// @file footprint_hwy.cpp
/// @brief The inner loop of footprint_avx2.cpp written with Highway (libhwy-dev) instead of
///        xsimd, for comparing the two: the same kernels (r for a vector of pixels of a row,
///        exp per lane with hwy/contrib/math's Exp, spread with FMAs), compiled once per
///        target by foreach_target.h and picked at run time by HWY_DYNAMIC_DISPATCH (target
///        detection in libhwy). This file is compiled with the baseline flags; built only where
///        Highway is found (bench/roofline/CMakeLists.txt).
///
/// Targets: AVX2, SSE4 and the portable fallback (HWY_SCALAR with g++ < 12.3, where Highway
/// 1.0.3 marks EMU128 broken; EMU128 otherwise). AVX-512 (AVX3) and SSSE3 are disabled so that
/// the comparison with the xsimd AVX2 kernels is like for like; define HWY_DISABLED_TARGETS
/// on the command line to change that.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_AVX3 | HWY_AVX3_DL | HWY_SSSE3)
#endif

#include "footprint_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

// Re-included once per target by foreach_target.h; the name is resolved on the include path
// (this directory is on it), not relative to this file.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "footprint_hwy.cpp"
#include <hwy/foreach_target.h> // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>

HWY_BEFORE_NAMESPACE();
namespace roofline {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

std::size_t SplatHwy(const std::vector<Footprint>& splats, Accumulators& acc)
{
    const hn::ScalableTag<float> d;
    const int lanes = int(hn::Lanes(d));
    const auto offsets = hn::Iota(d, 0.0f);
    std::size_t samples = 0;
    for (const Footprint& s : splats) {
        for (int y = 0; y < kTile; ++y) {
            float dy;
            int x0, x1;
            if (!rowSpan(s, y, dy, x0, x1)) continue;
            // r(dx) = qa dx^2 + (2 qb dy) dx + qc dy^2, a vector of pixels at once; lanes past
            // the span weigh 0 (the tile row, 16 wide, is a whole number of vectors).
            const auto a = hn::Set(d, s.qa), b = hn::Set(d, 2.0f * s.qb * dy), c = hn::Set(d, s.qc * dy * dy);
            const auto half2 = hn::Set(d, -0.5f);
            float* tau = acc.tau + y * kTile;
            float* m1 = acc.m1 + y * kTile;
            float* m2 = acc.m2 + y * kTile;
            for (int x = (x0 / lanes) * lanes; x <= x1; x += lanes) {
                const auto xs = hn::Add(offsets, hn::Set(d, float(x)));
                const auto dx = hn::Add(xs, hn::Set(d, 0.5f - s.cx));
                const auto r = hn::MulAdd(hn::MulAdd(a, dx, b), dx, c);
                const auto inside = hn::And(hn::Ge(xs, hn::Set(d, float(x0))), hn::Le(xs, hn::Set(d, float(x1))));
                const auto g = hn::IfThenElseZero(inside, hn::Exp(d, hn::Mul(half2, r)));
                hn::StoreU(hn::MulAdd(g, hn::Set(d, s.tau), hn::LoadU(d, tau + x)), d, tau + x);
                hn::StoreU(hn::MulAdd(g, hn::Set(d, s.w1), hn::LoadU(d, m1 + x)), d, m1 + x);
                hn::StoreU(hn::MulAdd(g, hn::Set(d, s.w2), hn::LoadU(d, m2 + x)), d, m2 + x);
            }
            samples += std::size_t(x1 - x0 + 1);
        }
    }
    return samples;
}

std::size_t CompositeHwy(Accumulators& acc)
{
    const hn::ScalableTag<float> d;
    const int lanes = int(hn::Lanes(d));
    const auto one = hn::Set(d, 1.0f);
    for (int p = 0; p < kPixels; p += lanes) {
        const auto t = hn::LoadU(d, acc.transmittance + p);
        const auto absorbed = hn::Sub(one, hn::Exp(d, hn::Neg(hn::LoadU(d, acc.tau + p))));
        hn::StoreU(hn::MulAdd(hn::Mul(t, absorbed), hn::LoadU(d, acc.emission + p), hn::LoadU(d, acc.colour + p)), d,
                   acc.colour + p);
        hn::StoreU(hn::Mul(t, hn::Sub(one, absorbed)), d, acc.transmittance + p);
        hn::StoreU(hn::Zero(d), d, acc.tau + p);
    }
    return kPixels;
}

std::int64_t TargetHwy() { return HWY_TARGET; }

} // namespace HWY_NAMESPACE
} // namespace roofline
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace roofline {

HWY_EXPORT(SplatHwy);
HWY_EXPORT(CompositeHwy);
HWY_EXPORT(TargetHwy);

std::size_t splatHwy(const std::vector<Footprint>& splats, Accumulators& acc)
{
    return HWY_DYNAMIC_DISPATCH(SplatHwy)(splats, acc);
}

std::size_t compositeHwy(Accumulators& acc) { return HWY_DYNAMIC_DISPATCH(CompositeHwy)(acc); }

const char* hwyTarget() { return hwy::TargetName(HWY_DYNAMIC_DISPATCH(TargetHwy)()); }

} // namespace roofline
#endif // HWY_ONCE
