/// @file simd_slab_compositor.cpp
/// @brief The slab compositor's SIMD backend (raster/slab_compositor.h): the tile sweep
///        (tile_compositor-inl.h) with a vector of pixels at a time in its two inner loops,
///        compiled by Highway for AVX2 and chosen at run time where the CPU has it
///        (HWY_DYNAMIC_DISPATCH). Within 1e-5 of the scalar backend, its test oracle
///        (docs/architecture.md#simd-rasteriser).
///
/// This file is compiled once per target: Highway's foreach_target.h includes it again with
/// HWY_TARGET set to each one, and everything between HWY_BEFORE_NAMESPACE and
/// HWY_AFTER_NAMESPACE lands in that target's namespace, compiled for its instruction set.
#include "raster/slab_compositor.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

// One x86 target, AVX2 (with FMA): older ones (SSSE3, SSE4) are left to the scalar backend, and
// AVX-512 (AVX3) was slower here (docs/architecture.md#simd-rasteriser). Each target compiles the
// whole tile sweep again.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SSSE3 | HWY_SSE4 | HWY_AVX3 | HWY_AVX3_DL)
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "raster/simd_slab_compositor.cpp"
#include <hwy/foreach_target.h>

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace vdb_ewa {
namespace detail {
namespace HWY_NAMESPACE {

#if HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR

// No vector unit: the scalar backend serves (simdSlabCompositor returns null).
SlabCompositor* makeSimdCompositor(int) { return nullptr; }

#else

namespace hn = hwy::HWY_NAMESPACE;
using FloatTag = hn::ScalableTag<float>;
using Floats = hn::Vec<FloatTag>;
constexpr int kLanes = int(hn::MaxLanes(FloatTag()));
static_assert(kTileSize % kLanes == 0, "a tile row is a whole number of vectors");

#include "raster/tile_compositor-inl.h"

/// The lanes of the vector at tile row position @a first that lie in [x0, x1].
inline hn::Mask<FloatTag> lanesIn(int first, int x0, int x1)
{
    const FloatTag d;
    const Floats x = hn::Iota(d, float(first));
    return hn::And(hn::Ge(x, hn::Set(d, float(x0))), hn::Le(x, hn::Set(d, float(x1))));
}

/// 1 - exp(-tau), 0 where tau <= 0 (slabAbsorbed).
inline Floats absorbedOf(Floats tau)
{
    const FloatTag d;
    return hn::IfThenElseZero(hn::Gt(tau, hn::Zero(d)), hn::Neg(hn::Expm1(d, hn::Neg(tau))));
}

template <int C>
void TileCompositor<C>::addRow(const Splat& s, const float* shares, const float* moments, const float* passSources, int y, int x0, int x1, float)
{
    const FloatTag d;
    // Whole vectors of the row, from the one holding x0: lanes outside x0..x1 weigh 0.
    const int first = x0 & ~(kLanes - 1);
    const int vectors = (x1 - first) / kLanes + 1;
    // r = qa dx^2 + 2 qb dx dy + qc dy^2 = qa (dx - e)^2 + h, e = -qb dy / qa, h = det Q dy^2 / qa:
    // the square completed in dx, once per row in double, leaves two terms >= 0 (no cancellation
    // in float for thin, tilted footprints). exp per lane: no serial chain along the row.
    const double qa = s.qa, qb = s.qb, qc = s.qc;
    const double dy = double(mY0 + y) + 0.5 - double(s.cy);
    const double e0 = double(mX0 + first) + 0.5 - double(s.cx) + qb * dy / qa;
    const double h = std::max((qa * qc - qb * qb) / qa * dy * dy, 0.0);
    const Floats vqa = hn::Set(d, float(qa)), vh = hn::Set(d, float(h)), minusHalf = hn::Set(d, -0.5f);
    Floats weights[kTileSize / kLanes];
    for (int v = 0; v < vectors; ++v) {
        const int x = first + v * kLanes;
        const Floats e = hn::Add(hn::Iota(d, float(v * kLanes)), hn::Set(d, float(e0)));
        const Floats r = hn::MulAdd(hn::Mul(vqa, e), e, vh);
        Floats w;
        if (mExp == ExpEvaluation::Table) {
            alignas(64) float lanes[kLanes];
            hn::Store(r, d, lanes);
            for (float& l : lanes) l = mTable->lookup(l);
            w = hn::Load(d, lanes);
        } else {
            w = hn::Exp(d, hn::Mul(minusHalf, r));
        }
        weights[v] = hn::IfThenElseZero(lanesIn(x, x0, x1), w);
    }
    forEachPlane(s, shares, moments, passSources, y * kTileSize + first, [&](float* plane, float factor) {
        const Floats f = hn::Set(d, factor);
        for (int v = 0; v < vectors; ++v) {
            float* at = plane + v * kLanes;
            hn::StoreU(hn::MulAdd(weights[v], f, hn::LoadU(d, at)), d, at);
        }
    });
}

template <int C>
void TileCompositor<C>::flushRow(std::int64_t slab, int y, int x0, int x1)
{
    const bool passes = mPassCount > 0 || mOptions.passes.depth || mOptions.passes.deep;
    const FloatTag d;
    const std::size_t base = slot(slab) * C * kTilePixels;
    const Floats zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    for (int first = x0 & ~(kLanes - 1); first <= x1; first += kLanes) {
        const int p = y * kTileSize + first;
        // 1. Per channel 1 - exp(-tau), the slab's mass and |T|^2 behind the whole slab.
        alignas(64) float absorbed[C][kLanes], mass[kLanes], t2After[kLanes];
        Floats m = zero, t2 = zero;
        for (int c = 0; c < 3; ++c) m = hn::Add(m, hn::LoadU(d, &mTau[base + std::size_t(channel(c)) * kTilePixels + std::size_t(p)]));
        for (int c = 0; c < C; ++c) {
            const Floats a = absorbedOf(hn::LoadU(d, &mTau[base + std::size_t(c) * kTilePixels + std::size_t(p)]));
            const Floats t = hn::Mul(hn::LoadU(d, &mT[c * kTilePixels + p]), hn::Sub(one, a));
            t2 = hn::MulAdd(t, t, t2);
            hn::Store(a, d, absorbed[c]);
        }
        hn::Store(m, d, mass);
        hn::Store(t2, d, t2After);
        // 2. Per lane: pixels with a surface to composite, or whose ray stops inside the slab,
        // take flushPixel's path; the others are composited below, lit per slab sample.
        alignas(64) float composite[kLanes], lit[C][kLanes], emission[C][kLanes], tBefore[C][kLanes], meanBefore[kLanes];
        for (int i = 0; i < kLanes; ++i) {
            const int x = first + i, q = p + i;
            composite[i] = 0.0f;
            for (int c = 0; c < C; ++c) lit[c][i] = 0.0f;
            if (x < x0 || x > x1) continue;
            if (mSurfacePending[q] || (mAlive[q] && mass[i] > 0.0f && t2After[i] * float(3 / C) < mCutoff)) {
                flushPixel(slab, q);
            } else if (mAlive[q]) {
                composite[i] = 1.0f;
                ++mComposites;
                if (passes) {
                    for (int c = 0; c < C; ++c) tBefore[c][i] = mT[c * kTilePixels + q];
                    meanBefore[i] = meanT(q);
                }
                if (mOptions.light && mass[i] > 0.0f) {
                    float l[C];
                    lightSlab(slab, q, mass[i], l);
                    for (int c = 0; c < C; ++c) lit[c][i] = l[c];
                }
            }
        }
        // 3. The exact front-to-back update (compositeSlab) of those lanes.
        const auto chosen = hn::Ne(hn::Load(d, composite), zero);
        Floats t2Now = zero;
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + std::size_t(c) * kTilePixels + std::size_t(p);
            const Floats tau = hn::LoadU(d, &mTau[i]), a = hn::Load(d, absorbed[c]);
            Floats emitted = zero, em = zero;
            if (!mEmission.empty()) {
                // Halo kernels (--prefilter) weigh negative: a slab's sums stay >= 0.
                em = hn::Max(hn::LoadU(d, &mEmission[i]), zero);
                emitted = hn::IfThenElse(hn::Gt(tau, hn::Set(d, 1e-7f)), hn::Mul(hn::Div(em, tau), a), em);
            }
            hn::Store(em, d, emission[c]);
            const Floats source = hn::MulAdd(hn::Set(d, mLightScale[c]), hn::Load(d, lit[c]), emitted);
            const auto update = hn::And(chosen, hn::Gt(tau, zero));
            float* colour = &mC[c * kTilePixels + p];
            float* transmittance = &mT[c * kTilePixels + p];
            const Floats t = hn::LoadU(d, transmittance);
            hn::StoreU(hn::IfThenElse(update, hn::MulAdd(t, source, hn::LoadU(d, colour)), hn::LoadU(d, colour)), d, colour);
            const Floats tNew = hn::IfThenElse(update, hn::Mul(t, hn::Sub(one, a)), t);
            hn::StoreU(tNew, d, transmittance);
            t2Now = hn::MulAdd(tNew, tNew, t2Now);
        }
        // 4. The passes' share (Z, deep sample, extra sources: flushPasses), vdb_render's ray
        // termination (|T|^2 < cutoff), and the slab's accumulators cleared (lanes outside
        // x0..x1 hold zeros: nothing outside the dirty box was added).
        alignas(64) float t2Lanes[kLanes];
        hn::Store(t2Now, d, t2Lanes);
        for (int i = 0; i < kLanes; ++i) {
            if (composite[i] == 0.0f) continue;
            if (passes) {
                float e[C], l[C];
                for (int c = 0; c < C; ++c) {
                    mTBefore[c] = tBefore[c][i];
                    e[c] = emission[c][i];
                    l[c] = lit[c][i];
                }
                flushPasses(slab, p + i, meanBefore[i], e, l);
            }
            if (t2Lanes[i] * float(3 / C) < mCutoff) terminate(p + i);
        }
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + std::size_t(c) * kTilePixels + std::size_t(p);
            hn::StoreU(zero, d, &mTau[i]);
            if (!mEmission.empty()) hn::StoreU(zero, d, &mEmission[i]);
            if (!mScatter.empty()) hn::StoreU(zero, d, &mScatter[i]);
            for (int k = 0; k < mPassCount; ++k) hn::StoreU(zero, d, &mPassEmission[passIndex(slab, k, c) + std::size_t(p)]);
        }
        if (!mMoment.empty()) {
            hn::StoreU(zero, d, &mMoment[slot(slab) * kTilePixels + std::size_t(p)]);
            hn::StoreU(zero, d, &mMoment2[slot(slab) * kTilePixels + std::size_t(p)]);
        }
    }
}

SlabCompositor* makeSimdCompositor(int channels)
{
    if (channels == 1) return new TileSweepCompositor<1>();
    return new TileSweepCompositor<3>();
}

#endif

const char* simdTargetName() { return hwy::TargetName(HWY_TARGET); }

} // namespace HWY_NAMESPACE
} // namespace detail
} // namespace vdb_ewa
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace vdb_ewa {
namespace detail {

HWY_EXPORT(makeSimdCompositor);
HWY_EXPORT(simdTargetName);

std::unique_ptr<SlabCompositor> simdSlabCompositor(int channels)
{
    return std::unique_ptr<SlabCompositor>(HWY_DYNAMIC_DISPATCH(makeSimdCompositor)(channels));
}

const char* simdTarget() { return HWY_DYNAMIC_DISPATCH(simdTargetName)(); }

} // namespace detail
} // namespace vdb_ewa
#endif
