/// @file simd_slab_compositor.cpp
/// @brief The slab compositor's SIMD backend (raster/slab_compositor.h): the tile sweep
///        (tile_compositor-inl.h) with a vector of pixels at a time in its two inner loops,
///        compiled by Highway for AVX2 and AVX-512, the best the CPU has chosen at run time
///        (HWY_DYNAMIC_DISPATCH). Within 1e-5 of the scalar backend, its test oracle
///        (docs/architecture.md#simd-rasteriser).
///
/// This file is compiled once per target: Highway's foreach_target.h includes it again with
/// HWY_TARGET set to each one, and everything between HWY_BEFORE_NAMESPACE and
/// HWY_AFTER_NAMESPACE lands in that target's namespace, compiled for its instruction set.
#include "raster/slab_compositor.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

// Two x86 targets: AVX2 (with FMA) and AVX-512 (AVX3), 8 and 16 lanes (docs/architecture.md#simd-
// rasteriser). Older ones (SSSE3, SSE4) are left to the scalar backend: each target compiles the
// whole tile sweep again.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_SSSE3 | HWY_SSE4 | HWY_AVX3_DL)
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

/// The lanes of the vector at tile pixel p whose byte flag (TileCompositor::mAlive,
/// mSurfacePending) at @a flags is set.
inline hn::Mask<FloatTag> byteLanes(const std::uint8_t* flags)
{
    const hn::RebindToSigned<FloatTag> di;
    const hn::Rebind<std::uint8_t, decltype(di)> du8;
    return hn::RebindMask(FloatTag(), hn::Ne(hn::PromoteTo(di, hn::LoadU(du8, flags)), hn::Zero(di)));
}

/// 1 - exp(-tau), 0 where tau <= 0 (slabAbsorbed).
inline Floats absorbedOf(Floats tau)
{
    const FloatTag d;
    return hn::IfThenElseZero(hn::Gt(tau, hn::Zero(d)), hn::Neg(hn::Expm1(d, hn::Neg(tau))));
}

/// slabLightIntegral per lane: front E(tau + k), E(x) = (1 - e^-x) / x (its series near 0).
inline Floats lightIntegral(Floats tau, Floats front, Floats logRatio)
{
    const FloatTag d;
    const Floats x = hn::Add(hn::Max(tau, hn::Zero(d)), logRatio);
    const Floats series = hn::Sub(hn::Set(d, 1.0f), hn::Mul(x, hn::Sub(hn::Set(d, 0.5f), hn::Div(x, hn::Set(d, 6.0f)))));
    const Floats mean = hn::IfThenElse(hn::Lt(hn::Abs(x), hn::Set(d, 1e-3f)), series, hn::Div(hn::Neg(hn::Expm1(d, hn::Neg(x))), x));
    return hn::Mul(hn::Max(front, hn::Set(d, kLightFloor)), mean);
}

using IntTag = hn::RebindToSigned<FloatTag>;
using Ints = hn::Vec<IntTag>;
using DoubleTag = hn::Repartition<double, FloatTag>; // half the lanes
using Doubles = hn::Vec<DoubleTag>;

/// A vector of points on pixel rays in light-map coordinates, as LightMap::cell reads them: the
/// lattice cell (i, j) clamped to [-1, nu] x [-1, nv], bilinear weights (a, b), and along the
/// light the sample floor(w) and w - floor(w) (the same values the scalar lookup forms in double).
struct MapPoints
{
    Ints i, j, kw;
    Floats a, b, fw;
};

/// The points base + z dir - @a shift of the lanes at tile pixel @a p, z = z0 + u thickness
/// (@a shift: motion blur's mean move in map coordinates, TileCompositor::shiftOf).
inline MapPoints mapPoints(const LightMap::Lattice& map, const double (*base)[kTilePixels], const double (*dir)[kTilePixels], int p,
    Floats u, double z0, double thickness, const Floats (&shift)[3])
{
    const DoubleTag dd;
    const hn::Rebind<std::int32_t, DoubleTag> di;
    const hn::Rebind<float, DoubleTag> df;
    constexpr int kHalf = kLanes / 2;
    hn::Vec<decltype(di)> i[2], j[2], kw[2];
    hn::Vec<decltype(df)> a[2], b[2], fw[2];
    const Doubles lo = hn::Set(dd, -1.0), wLimit = hn::Set(dd, 1073741824.0); // 2^30: far past any ray's samples
    for (int h = 0; h < 2; ++h) {
        const Doubles uh = h == 0 ? hn::PromoteTo(dd, hn::LowerHalf(u)) : hn::PromoteTo(dd, hn::UpperHalf(hn::Half<FloatTag>(), u));
        const Doubles z = hn::MulAdd(uh, hn::Set(dd, thickness), hn::Set(dd, z0));
        const int q = p + h * kHalf;
        const auto half = [&](const Floats& v) { return h == 0 ? hn::PromoteTo(dd, hn::LowerHalf(v)) : hn::PromoteTo(dd, hn::UpperHalf(hn::Half<FloatTag>(), v)); };
        const Doubles x = hn::Sub(hn::MulAdd(z, hn::LoadU(dd, &dir[0][q]), hn::LoadU(dd, &base[0][q])), half(shift[0]));
        const Doubles y = hn::Sub(hn::MulAdd(z, hn::LoadU(dd, &dir[1][q]), hn::LoadU(dd, &base[1][q])), half(shift[1]));
        const Doubles w = hn::Min(hn::Max(hn::Sub(hn::MulAdd(z, hn::LoadU(dd, &dir[2][q]), hn::LoadU(dd, &base[2][q])), half(shift[2])), hn::Neg(wLimit)), wLimit);
        const Doubles fu = hn::Floor(x), fv = hn::Floor(y), fk = hn::Floor(w);
        i[h] = hn::DemoteTo(di, hn::Min(hn::Max(fu, lo), hn::Set(dd, double(map.nu))));
        j[h] = hn::DemoteTo(di, hn::Min(hn::Max(fv, lo), hn::Set(dd, double(map.nv))));
        kw[h] = hn::DemoteTo(di, fk);
        a[h] = hn::DemoteTo(df, hn::Sub(x, fu));
        b[h] = hn::DemoteTo(df, hn::Sub(y, fv));
        fw[h] = hn::DemoteTo(df, hn::Sub(w, fk));
    }
    const IntTag dint;
    const FloatTag d;
    return {hn::Combine(dint, i[1], i[0]), hn::Combine(dint, j[1], j[0]), hn::Combine(dint, kw[1], kw[0]),
        hn::Combine(d, a[1], a[0]), hn::Combine(d, b[1], b[0]), hn::Combine(d, fw[1], fw[0])};
}

/// Lanes not lit look up nothing: their points go off the lattice (i = nu, j = nv, so the four
/// rays around them are off it too). Their gathers then read ray 0, which a map marched on
/// demand marches first; no lane reads a ray that another thread may be marching
/// (raster/light_on_demand.h).
template <typename M>
inline void offLatticeUnless(const LightMap::Lattice& map, M lit, MapPoints& q)
{
    const IntTag di;
    const auto on = hn::RebindMask(di, lit);
    q.i = hn::IfThenElse(on, q.i, hn::Set(di, map.nu));
    q.j = hn::IfThenElse(on, q.j, hn::Set(di, map.nv));
}

/// LightMap::depthOnRay for lattice ray (i, j) at each lane's points (0 off the lattice, on a
/// ray without density, or past its stored samples).
inline Floats depthOnRays(const LightMap::Lattice& map, Ints i, Ints j, Ints kw, Floats fw)
{
    const IntTag di;
    const FloatTag d;
    const Ints zero = hn::Zero(di), one = hn::Set(di, 1);
    const auto onLattice = hn::And(hn::And(hn::Gt(i, hn::Set(di, -1)), hn::Lt(i, hn::Set(di, map.nu))),
        hn::And(hn::Gt(j, hn::Set(di, -1)), hn::Lt(j, hn::Set(di, map.nv))));
    const Ints ray = hn::IfThenElseZero(onLattice, hn::Add(hn::Mul(j, hn::Set(di, map.nu)), i));
    const Ints count = hn::IfThenElseZero(onLattice, hn::GatherIndex(di, map.count, ray));
    // Below the stored range: its first value (x = max(w - kLo, 0)).
    const Ints rel = hn::Sub(kw, hn::GatherIndex(di, map.kLo, ray));
    const auto below = hn::Lt(rel, zero);
    const Ints k = hn::IfThenZeroElse(below, rel);
    const Floats f = hn::IfThenZeroElse(hn::RebindMask(d, below), fw);
    const auto stored = hn::Lt(k, count); // also false where count is 0
    const auto hasNext = hn::And(stored, hn::Lt(hn::Add(k, one), count));
    const Ints at = hn::Add(hn::GatherIndex(di, map.offset, ray), k);
    const Floats here = hn::IfThenElseZero(hn::RebindMask(d, stored), hn::GatherIndex(d, map.depth, hn::IfThenElseZero(stored, at)));
    const Floats next = hn::IfThenElseZero(hn::RebindMask(d, hasNext), hn::GatherIndex(d, map.depth, hn::IfThenElseZero(hasNext, hn::Add(at, one))));
    return hn::IfThenElseZero(hn::RebindMask(d, stored), hn::MulAdd(f, hn::Sub(next, here), here));
}

/// LightMap::densityDepth per lane: bilinear across the light in the four rays around each point.
inline Floats densityDepths(const LightMap::Lattice& map, const MapPoints& q)
{
    const IntTag di;
    const FloatTag d;
    if (!map.depth) return hn::Zero(d);
    const Ints one = hn::Set(di, 1);
    const Ints i1 = hn::Add(q.i, one), j1 = hn::Add(q.j, one);
    const Floats d00 = depthOnRays(map, q.i, q.j, q.kw, q.fw), d10 = depthOnRays(map, i1, q.j, q.kw, q.fw);
    const Floats d01 = depthOnRays(map, q.i, j1, q.kw, q.fw), d11 = depthOnRays(map, i1, j1, q.kw, q.fw);
    const Floats oneF = hn::Set(d, 1.0f), ra = hn::Sub(oneF, q.a), rb = hn::Sub(oneF, q.b);
    return hn::Add(hn::Mul(rb, hn::Add(hn::Mul(ra, d00), hn::Mul(q.a, d10))), hn::Mul(q.b, hn::Add(hn::Mul(ra, d01), hn::Mul(q.a, d11))));
}

/// LightMap::logTransmittanceOfDepth per lane, for @a channels channels (1: the grey value).
inline void logTransmittances(const LightMap::Lattice& map, Floats depth, int channels, Floats* logT)
{
    const FloatTag d;
    const Floats zero = hn::Zero(d);
    const auto positive = hn::Gt(depth, zero);
    if (map.grey || channels == 1) {
        // |T|^2 = 3 T^2 < cutoff where T < sqrt(cutoff / 3): the floor, in the log domain.
        const Floats grey = hn::IfThenElseZero(positive, hn::Max(hn::Mul(hn::Set(d, -map.extinction[0]), depth), hn::Set(d, map.logGreyFloor)));
        for (int c = 0; c < channels; ++c) logT[c] = grey;
        return;
    }
    // vdb_render's shadow ray stops at the stop depth and keeps the light it had there.
    const Floats kept = hn::IfThenElseZero(positive, hn::Min(depth, hn::Set(d, map.stopDepth)));
    for (int c = 0; c < 3; ++c) logT[c] = hn::Mul(hn::Set(d, -map.extinction[c]), kept);
}

/// The footprint's weights stepped down the tile: r = d^T Q d is quadratic in y, so at each
/// pixel exp(-r/2) on the next row is this row's times a ratio m = exp(-(qb dx + qc (dy + 1/2))),
/// and the next row's ratio is this one's times exp(-qc): Sec. 7.1's forward differencing in
/// the exponential domain, down the rows as the scalar backend steps along them, two
/// multiplications a row in place of an exp. Seeded exactly every kSeedRows rows (the products'
/// rounding stays below 1e-6 relative), and only where r < kMaxStepR over the splat's box in the
/// tile, so that neither a weight nor a ratio leaves float's range.
template <int C> struct TileCompositor<C>::RowSteps
{
    static constexpr int kVectors = kTileSize / kLanes;
    static constexpr int kSeedRows = 8;
    static constexpr double kMaxStepR = 160.0; // exp(-80) = 1.8e-35 > FLT_MIN, exp(80) < FLT_MAX
    bool on = false;
    int row = 0, seeded = 0; // the row the weights are at, and the last exact one
    Floats weight[kVectors], ratio[kVectors], step;
};

template <int C>
typename TileCompositor<C>::RowSteps TileCompositor<C>::startRows(const Splat& s, int lx0, int ly0, int lx1, int ly1) const
{
    RowSteps steps;
    // --exp incremental (forward differencing; exact and table evaluate every sample), on a
    // footprint a few rows tall.
    if (mExp != ExpEvaluation::Incremental || ly1 - ly0 < 2) return steps;
    const double qa = s.qa, qb = s.qb, qc = s.qc;
    double most = 0.0; // r is convex: its largest over the box is at a corner
    for (int corner = 0; corner < 4; ++corner) {
        const double dx = double(mX0 + ((corner & 1) ? lx1 : lx0)) + 0.5 - double(s.cx);
        const double dy = double(mY0 + ((corner & 2) ? ly1 : ly0)) + 0.5 - double(s.cy);
        most = std::max(most, qa * dx * dx + 2.0 * qb * dx * dy + qc * dy * dy);
    }
    steps.on = most < RowSteps::kMaxStepR;
    steps.row = steps.seeded = ly0 - RowSteps::kSeedRows; // seeded at the first row
    steps.step = hn::Set(FloatTag(), float(std::exp(-qc)));
    return steps;
}

template <int C>
void TileCompositor<C>::addRow(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift, int y, int x0,
    int x1, float, RowSteps& steps)
{
    const FloatTag d;
    // Whole vectors of the row, from the one holding x0: lanes outside x0..x1 weigh 0.
    const int first = x0 & ~(kLanes - 1);
    const int vectors = (x1 - first) / kLanes + 1;
    const double qa = s.qa, qb = s.qb, qc = s.qc;
    const Floats minusHalf = hn::Set(d, -0.5f);
    // exp(-r/2) on tile row @a row at the @a count vectors from tile column @a from: r =
    // qa dx^2 + 2 qb dx dy + qc dy^2 = qa (dx - e)^2 + h, e = -qb dy / qa, h = det Q dy^2 / qa,
    // the square completed in dx, once per row in double, leaves two terms >= 0 (no
    // cancellation in float for thin, tilted footprints). exp per lane: no serial chain.
    const auto exactRow = [&](int row, int from, int count, Floats* out) {
        const double dy = double(mY0 + row) + 0.5 - double(s.cy);
        const double e0 = double(mX0 + from) + 0.5 - double(s.cx) + qb * dy / qa;
        const double h = std::max((qa * qc - qb * qb) / qa * dy * dy, 0.0);
        const Floats vqa = hn::Set(d, float(qa)), vh = hn::Set(d, float(h));
        for (int v = 0; v < count; ++v) {
            const Floats e = hn::Add(hn::Iota(d, float(v * kLanes)), hn::Set(d, float(e0)));
            const Floats r = hn::MulAdd(hn::Mul(vqa, e), e, vh);
            if (mExp == ExpEvaluation::Table) {
                alignas(64) float lanes[kLanes];
                hn::Store(r, d, lanes);
                for (float& l : lanes) l = mTable->lookup(l);
                out[v] = hn::Load(d, lanes);
            } else {
                out[v] = hn::Exp(d, hn::Mul(minusHalf, r));
            }
        }
    };
    Floats raw[kTileSize / kLanes];
    if (steps.on) {
        if (y - steps.seeded >= RowSteps::kSeedRows) {
            // Exact again: the weights and the ratios to the next row, for the whole tile row.
            exactRow(y, 0, RowSteps::kVectors, steps.weight);
            const double dy = double(mY0 + y) + 0.5 - double(s.cy);
            for (int v = 0; v < RowSteps::kVectors; ++v) {
                const double dx0 = double(mX0 + v * kLanes) + 0.5 - double(s.cx);
                const Floats exponent = hn::MulAdd(hn::Set(d, float(-qb)), hn::Iota(d, 0.0f), hn::Set(d, float(-(qb * dx0 + qc * (dy + 0.5)))));
                steps.ratio[v] = hn::Exp(d, exponent);
            }
            steps.row = steps.seeded = y;
        }
        for (; steps.row < y; ++steps.row) {
            for (int v = 0; v < RowSteps::kVectors; ++v) {
                steps.weight[v] = hn::Mul(steps.weight[v], steps.ratio[v]);
                steps.ratio[v] = hn::Mul(steps.ratio[v], steps.step);
            }
        }
        for (int v = 0; v < vectors; ++v) raw[v] = steps.weight[first / kLanes + v];
    } else {
        exactRow(y, first, vectors, raw);
    }
    const Floats edge = hn::Set(d, mOptions.taperEdge); // SplatOptions::taper
    Floats weights[kTileSize / kLanes];
    for (int v = 0; v < vectors; ++v) weights[v] = hn::IfThenElseZero(lanesIn(first + v * kLanes, x0, x1), hn::Max(hn::Sub(raw[v], edge), hn::Zero(d)));
    forEachPlane(s, shares, moments, passSources, shift, y * kTileSize + first, [&](float* plane, float factor) {
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
    // meanT at the lanes from tile pixel @a at, in its order of operations.
    const auto meanOf = [&](int at) {
        return hn::Div(hn::Add(hn::Add(hn::LoadU(d, &mT[at]), hn::LoadU(d, &mT[channel(1) * kTilePixels + at])), hn::LoadU(d, &mT[channel(2) * kTilePixels + at])),
            hn::Set(d, 3.0f));
    };
    for (int first = x0 & ~(kLanes - 1); first <= x1; first += kLanes) {
        const int p = y * kTileSize + first;
        // 1. Per channel 1 - exp(-tau), the slab's mass and |T|^2 behind the whole slab.
        // With shutter layers, each layer's own (layerAbsorbed) and their mean transmittance.
        alignas(64) float absorbed[C][kLanes], mass[kLanes], t2After[kLanes];
        alignas(64) float layerAbsorbed[kMaxShutterLayers][C][kLanes];
        const int layers = mLayerT.empty() ? 0 : mLayers;
        Floats m = zero, t2 = zero;
        for (int c = 0; c < 3; ++c) m = hn::Add(m, hn::LoadU(d, &mTau[base + std::size_t(channel(c)) * kTilePixels + std::size_t(p)]));
        for (int c = 0; c < C; ++c) {
            const Floats a = absorbedOf(hn::LoadU(d, &mTau[base + std::size_t(c) * kTilePixels + std::size_t(p)]));
            Floats t = hn::Mul(hn::LoadU(d, &mT[c * kTilePixels + p]), hn::Sub(one, a));
            if (layers) {
                t = zero;
                for (int k = 0; k < layers; ++k) {
                    const Floats ak = absorbedOf(hn::LoadU(d, &mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]));
                    hn::Store(ak, d, layerAbsorbed[k][c]);
                    t = hn::MulAdd(hn::LoadU(d, &mLayerT[layerT(k, c) + std::size_t(p)]), hn::Sub(one, ak), t);
                }
                t = hn::Div(t, hn::Set(d, float(layers)));
            }
            t2 = hn::MulAdd(t, t, t2);
            hn::Store(a, d, absorbed[c]);
        }
        hn::Store(m, d, mass);
        hn::Store(t2, d, t2After);
        // 2. Per lane: pixels with a surface to composite take flushPixel's path, and so do those
        // whose ray stops inside the slab under shutter layers; the others are composited
        // below, lit per slab sample, those whose ray stops inside the slab with the part in
        // front of the crossing (cut: its fraction, terminationFraction, 1 for the others) as
        // flushPixel composites it.
        alignas(64) float lit[C][kLanes], litColoured[C][kLanes], emission[C][kLanes], tBefore[C][kLanes], meanBefore[kLanes];
        alignas(64) float lighted[kLanes], cut[kLanes], lanes[kLanes];
        const bool cutHere = layers == 0;
        const auto inRange = lanesIn(first, x0, x1);
        const auto alive = byteLanes(mAlive + p);
        const auto massive = hn::Gt(hn::Load(d, mass), zero);
        const auto stops = hn::And(hn::And(alive, massive), hn::Lt(hn::Mul(hn::Load(d, t2After), hn::Set(d, float(3 / C))), hn::Set(d, mCutoff)));
        const auto pending = byteLanes(mSurfacePending + p);
        const auto alone = hn::And(inRange, cutHere ? pending : hn::Or(pending, stops));
        if (!hn::AllFalse(d, alone)) {
            hn::Store(hn::IfThenElseZero(alone, one), d, lanes);
            for (int i = 0; i < kLanes; ++i)
                if (lanes[i] != 0.0f) flushPixel(slab, p + i);
        }
        const auto chosen = hn::AndNot(alone, hn::And(inRange, alive));
        mComposites += std::uint64_t(hn::CountTrue(d, chosen));
        hn::Store(one, d, cut);
        bool anyCut = false;
        if (cutHere && !hn::AllFalse(d, hn::And(chosen, stops))) {
            hn::Store(hn::IfThenElseZero(hn::And(chosen, stops), one), d, lanes);
            for (int i = 0; i < kLanes; ++i) {
                if (lanes[i] == 0.0f) continue;
                cut[i] = terminationFraction(slab, base, p + i);
                anyCut = anyCut || cut[i] < 1.0f;
            }
        }
        if (passes) {
            for (int c = 0; c < C; ++c) hn::Store(hn::LoadU(d, &mT[c * kTilePixels + p]), d, tBefore[c]);
            hn::Store(meanOf(p), d, meanBefore);
        }
        const auto lightedLanes = mOptions.lit() ? hn::And(chosen, massive) : hn::Lt(one, zero);
        const bool anyLighted = !hn::AllFalse(d, lightedLanes);
        hn::Store(hn::IfThenElseZero(lightedLanes, one), d, lighted);
        // 3. The light on those lanes' layers (lightSlab: the slab's mass with the mean and
        // variance of its position, lit at its front and back from each light's map, lightAt),
        // times the scattering weight (the lights summed: lit per unit colour, the source with
        // each light's colour), then the exact front-to-back update (compositeSlab).
        Floats u0 = zero, u1 = zero;
        if (anyLighted) {
            const std::size_t m = slot(slab) * kTilePixels + std::size_t(p);
            const Floats massLanes = hn::Load(d, mass);
            const Floats mean = hn::Min(hn::Max(hn::Div(hn::LoadU(d, &mMoment[m]), massLanes), zero), one);
            const Floats spread = hn::Sub(hn::Div(hn::LoadU(d, &mMoment2[m]), massLanes), hn::Mul(mean, mean));
            const Floats half = hn::Sqrt(hn::Mul(hn::Set(d, 3.0f), hn::Max(spread, zero)));
            u0 = hn::IfThenElseZero(lightedLanes, hn::Max(hn::Sub(mean, half), zero));
            u1 = hn::IfThenElseZero(lightedLanes, hn::Min(hn::Add(mean, half), one));
        }
        // Per channel, once for every light: the optical depth, the scattering weight, and the
        // emission as the source's start. Lanes whose ray stops inside the slab keep the part
        // in front of the crossing (flushPixel): tau, emission and absorption of that part, the
        // light (looked up across the whole slab's layer) kept in proportion to the absorption.
        Floats tau[C], lightDepth[C], weight[C], source[C], litSum[C], colouredSum[C], kept[C];
        const Floats cutLanes = hn::Load(d, cut);
        const auto cutMask = hn::Lt(cutLanes, one);
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + std::size_t(c) * kTilePixels + std::size_t(p);
            lightDepth[c] = tau[c] = hn::LoadU(d, &mTau[i]);
            kept[c] = one;
            if (anyCut) {
                const Floats whole = hn::Load(d, absorbed[c]);
                tau[c] = hn::Mul(tau[c], cutLanes);
                const Floats front = absorbedOf(tau[c]);
                const auto absorbing = hn::Gt(whole, zero);
                kept[c] = hn::IfThenElse(cutMask, hn::IfThenElseZero(absorbing, hn::Div(front, hn::IfThenElse(absorbing, whole, one))), one);
                hn::Store(front, d, absorbed[c]);
            }
            weight[c] = hn::Max(hn::LoadU(d, mScatter.empty() ? &mTau[i] : &mScatter[i]), zero);
            Floats emitted = zero, em = zero;
            if (!mEmission.empty()) {
                // Halo kernels (--prefilter) weigh negative: a slab's sums stay >= 0.
                em = hn::Mul(hn::Max(hn::LoadU(d, &mEmission[i]), zero), cutLanes);
                emitted = hn::IfThenElse(hn::Gt(tau[c], hn::Set(d, 1e-7f)), hn::Mul(hn::Div(em, tau[c]), hn::Load(d, absorbed[c])), em);
            }
            hn::Store(em, d, emission[c]);
            source[c] = emitted;
            litSum[c] = colouredSum[c] = zero;
        }
        // The lanes' light for optical depths @a depth and scattering weights @a scatter, their
        // material moved by shutter layer @a layer's mean move (shiftOf: with no piece on some
        // layers only, layer 0's is the whole's), the lights summed into @a litOut and
        // @a colouredOut.
        // The phase function and the octaves, where the light is shaped (shapedLightLayer).
        const ScatteringOctaves* octaves = shaped() ? &mOptions.model->octaves() : nullptr;
        const auto lightLanes = [&](const Floats (&depth)[C], const Floats (&scatter)[C], int layer, Floats (&litOut)[C], Floats (&colouredOut)[C]) {
            // Motion blur: the lanes' mean move (world), 0 where nothing moved (shiftOf).
            Floats moved[3] = {zero, zero, zero};
            if (!mShift.empty()) {
                const std::size_t m = shiftIndex(slab, layer) + std::size_t(p);
                Floats sum[kShiftPlanes];
                for (int k = 0; k < kShiftPlanes; ++k) sum[k] = hn::LoadU(d, &mShift[m + std::size_t(k) * kTilePixels]);
                const auto some = hn::Gt(sum[3], zero);
                for (int k = 0; k < 3; ++k) moved[k] = hn::IfThenElseZero(some, hn::Div(sum[k], sum[3]));
            }
            for (std::size_t light = 0; light < mOptions.lights.size(); ++light) {
                const LightMap::Lattice map = mOptions.lights[light].map->lattice();
                const double z = mOptions.slabs.start(slab), thickness = mOptions.slabs.thickness;
                const LightRays& rays = mRays[light];
                Floats log0[3], log1[3];
                // The move in the map's coordinates (LightMap::direction, a linear map).
                Floats shift[3] = {zero, zero, zero};
                if (!mShift.empty()) {
                    for (int k = 0; k < 3; ++k) {
                        Vec3d axis(0.0);
                        axis[k] = 1.0;
                        const Vec3d column = mOptions.lights[light].map->direction(axis);
                        for (int i = 0; i < 3; ++i) shift[i] = hn::MulAdd(hn::Set(d, float(column[i])), moved[k], shift[i]);
                    }
                }
                MapPoints q0 = mapPoints(map, rays.base, rays.dir, p, u0, z, thickness, shift), q1 = mapPoints(map, rays.base, rays.dir, p, u1, z, thickness, shift);
                offLatticeUnless(map, lightedLanes, q0);
                offLatticeUnless(map, lightedLanes, q1);
                logTransmittances(map, densityDepths(map, q0), C, log0);
                logTransmittances(map, densityDepths(map, q1), C, log1);
                const Floats floor = hn::Set(d, kLogLightFloor); // as lightLogRatio
                for (int c = 0; c < C; ++c) {
                    const Floats front = hn::Exp(d, log0[c]);
                    const Floats logRatio = hn::Sub(hn::Max(log0[c], floor), hn::Max(log1[c], floor));
                    const Floats l = hn::IfThenElseZero(lightedLanes, hn::Mul(scatter[c], lightIntegral(depth[c], front, logRatio)));
                    litOut[c] = hn::Add(litOut[c], l);
                    if (!octaves) {
                        colouredOut[c] = hn::MulAdd(hn::Set(d, mOptions.lights[light].scale[c]), l, colouredOut[c]);
                        continue;
                    }
                    // The phase function and the octaves (shapedLightLayer): octave i with the
                    // light's log transmittance times b^i, weighed by the pixel's a^i x phase.
                    Floats sum = hn::Mul(hn::LoadU(d, &mPhase[phaseIndex(light, 0) + std::size_t(p)]), l);
                    const Floats logFront = hn::Max(log0[c], floor);
                    for (int i = 1; i < octaves->count(); ++i) {
                        const Floats b = hn::Set(d, float(octaves->extinction(i)));
                        const Floats frontI = hn::Exp(d, hn::Mul(b, logFront));
                        const Floats li = hn::IfThenElseZero(lightedLanes, hn::Mul(scatter[c], lightIntegral(depth[c], frontI, hn::Mul(b, logRatio))));
                        sum = hn::MulAdd(hn::LoadU(d, &mPhase[phaseIndex(light, i) + std::size_t(p)]), li, sum);
                    }
                    colouredOut[c] = hn::MulAdd(hn::Set(d, mOptions.lights[light].scale[c]), sum, colouredOut[c]);
                }
            }
            if (mOptions.pointLights) {
                // Point lights: each lit lane's layer looked up lane by lane (pointLightAt: a cube
                // of rays, not a lattice the vector lookup reads), then lit as the lights above.
                alignas(64) float lane0[kLanes], lane1[kLanes], front[3][kLanes], logRatio[3][kLanes], falloff[kLanes];
                alignas(64) float weights[ScatteringOctaves::kMax][kLanes];
                hn::Store(u0, d, lane0);
                hn::Store(u1, d, lane1);
                const PointLights& points = *mOptions.pointLights;
                for (std::size_t light = 0; light < points.maps().size(); ++light) {
                    for (int i = 0; i < kLanes; ++i) {
                        std::array<float, 3> f{1.0f, 1.0f, 1.0f}, r{0.0f, 0.0f, 0.0f};
                        float g = 0.0f, w[ScatteringOctaves::kMax] = {};
                        if (lighted[i] != 0.0f) {
                            const Vec3d moved = shiftOf(slab, p + i, layer);
                            pointLightAt(light, p + i, slab, lane0[i], lane1[i], moved, f, r, g);
                            if (octaves) pointOctaveWeights(light, p + i, slab, lane0[i], lane1[i], moved, w);
                        }
                        for (int c = 0; c < 3; ++c) {
                            front[c][i] = f[std::size_t(c)];
                            logRatio[c][i] = r[std::size_t(c)];
                        }
                        falloff[i] = g;
                        for (int k = 0; octaves && k < octaves->count(); ++k) weights[k][i] = w[k];
                    }
                    const Floats g = hn::Load(d, falloff);
                    const Floats floor = hn::Set(d, kLightFloor);
                    for (int c = 0; c < C; ++c) {
                        const Floats f = hn::Load(d, front[c]), r = hn::Load(d, logRatio[c]);
                        const Floats l = hn::IfThenElseZero(lightedLanes, hn::Mul(scatter[c], lightIntegral(depth[c], f, r)));
                        litOut[c] = hn::Add(litOut[c], l);
                        Floats sum = l;
                        if (octaves) {
                            sum = hn::Mul(hn::Load(d, weights[0]), l);
                            const Floats logFront = hn::Log(d, hn::Max(f, floor));
                            for (int i = 1; i < octaves->count(); ++i) {
                                const Floats b = hn::Set(d, float(octaves->extinction(i)));
                                const Floats frontI = hn::Exp(d, hn::Mul(b, logFront));
                                const Floats li = hn::IfThenElseZero(lightedLanes, hn::Mul(scatter[c], lightIntegral(depth[c], frontI, hn::Mul(b, r))));
                                sum = hn::MulAdd(hn::Load(d, weights[i]), li, sum);
                            }
                        }
                        colouredOut[c] = hn::MulAdd(hn::Mul(hn::Set(d, float(points.scale(light)[std::size_t(c)])), g), sum, colouredOut[c]);
                    }
                }
            }
        };
        // Lanes whose optical depth is on every layer (no piece of a path on some) are lit once.
        bool perLayer = false;
        for (int k = 1; anyLighted && layers && !mShift.empty() && k < layers && !perLayer; ++k) {
            // (The splats on every layer add the same to each, in the same order: ownLayers.)
            perLayer = !hn::AllTrue(d, hn::Eq(hn::LoadU(d, &mShift[shiftIndex(slab, k) + 3 * kTilePixels + std::size_t(p)]),
                                            hn::LoadU(d, &mShift[shiftIndex(slab, 0) + 3 * kTilePixels + std::size_t(p)])));
        }
        if (perLayer) {
            // Motion blur's shutter layers with the light following the material: each layer
            // lit where its own material came from, by its own optical depth, seen through its
            // own transmittance, returned per unit of the mean absorption (lightSlab).
            Floats seen[C], litSeen[C], colouredSeen[C];
            for (int c = 0; c < C; ++c) seen[c] = litSeen[c] = colouredSeen[c] = zero;
            for (int k = 0; k < layers; ++k) {
                Floats depth[C], scatter[C], litK[C], colouredK[C];
                for (int c = 0; c < C; ++c) {
                    depth[c] = hn::LoadU(d, &mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]);
                    const Floats positive = hn::Max(depth[c], zero);
                    scatter[c] = mScatter.empty() ? positive
                                                  : hn::IfThenElse(hn::Gt(tau[c], zero), hn::Div(hn::Mul(weight[c], positive), hn::IfThenElse(hn::Gt(tau[c], zero), tau[c], one)), weight[c]);
                    litK[c] = colouredK[c] = zero;
                }
                lightLanes(depth, scatter, k, litK, colouredK);
                for (int c = 0; c < C; ++c) {
                    const Floats t = hn::LoadU(d, &mLayerT[layerT(k, c) + std::size_t(p)]);
                    seen[c] = hn::MulAdd(t, hn::Load(d, layerAbsorbed[k][c]), seen[c]);
                    litSeen[c] = hn::MulAdd(t, litK[c], litSeen[c]);
                    colouredSeen[c] = hn::MulAdd(t, colouredK[c], colouredSeen[c]);
                }
            }
            for (int c = 0; c < C; ++c) {
                const Floats a = hn::Load(d, absorbed[c]);
                const auto through = hn::And(hn::Gt(seen[c], hn::Set(d, kSeenFloor)), hn::Gt(a, zero));
                const Floats over = hn::IfThenElse(through, seen[c], hn::Set(d, float(layers)));
                // (The ratio first: the transmittances may be denormal. Nothing seen through any
                // layer: their plain mean, which composites nothing.)
                const Floats times = hn::IfThenElse(through, a, one);
                litSum[c] = hn::Mul(hn::Div(litSeen[c], over), times);
                colouredSum[c] = hn::Mul(hn::Div(colouredSeen[c], over), times);
                source[c] = hn::Add(source[c], colouredSum[c]);
            }
        } else if (anyLighted) {
            lightLanes(lightDepth, weight, 0, litSum, colouredSum);
            for (int c = 0; c < C; ++c) {
                litSum[c] = hn::Mul(litSum[c], kept[c]);
                colouredSum[c] = hn::Mul(colouredSum[c], kept[c]);
                source[c] = hn::Add(source[c], colouredSum[c]);
            }
        }
        Floats t2Now = zero;
        for (int c = 0; c < C; ++c) {
            const Floats a = hn::Load(d, absorbed[c]);
            hn::Store(litSum[c], d, lit[c]);
            hn::Store(colouredSum[c], d, litColoured[c]);
            // Emitters without optical depth (emission grids) add their light too.
            const auto update = hn::And(chosen, hn::Or(hn::Gt(tau[c], zero), hn::Gt(hn::Load(d, emission[c]), zero)));
            float* colour = &mC[c * kTilePixels + p];
            float* transmittance = &mT[c * kTilePixels + p];
            const Floats t = hn::LoadU(d, transmittance);
            Floats seenThrough = t, tNew = hn::IfThenElse(update, hn::Mul(t, hn::Sub(one, a)), t);
            if (layers) {
                // Motion blur's shutter layers (compositeLayers): the colour seen through each
                // layer by its own absorption, each layer's transmittance by its own depth.
                const auto thick = hn::And(chosen, hn::Gt(tau[c], zero));
                Floats seen = zero, left = zero;
                for (int k = 0; k < layers; ++k) {
                    float* tk = &mLayerT[layerT(k, c) + std::size_t(p)];
                    const Floats ak = hn::Load(d, layerAbsorbed[k][c]);
                    const Floats before = hn::LoadU(d, tk);
                    seen = hn::MulAdd(before, ak, seen);
                    const Floats after = hn::IfThenElse(thick, hn::Mul(before, hn::Sub(one, ak)), before);
                    hn::StoreU(after, d, tk);
                    left = hn::Add(left, after);
                }
                const Floats count = hn::Set(d, float(layers));
                const auto absorbing = hn::And(thick, hn::Gt(a, zero));
                seenThrough = hn::IfThenElse(absorbing, hn::Div(seen, hn::Mul(count, hn::IfThenElse(absorbing, a, one))), t);
                tNew = hn::IfThenElse(thick, hn::Div(left, count), t);
            }
            hn::StoreU(hn::IfThenElse(update, hn::MulAdd(seenThrough, source[c], hn::LoadU(d, colour)), hn::LoadU(d, colour)), d, colour);
            hn::StoreU(tNew, d, transmittance);
            t2Now = hn::MulAdd(tNew, tNew, t2Now);
        }
        // 5. The passes' share (Z, deep sample, extra sources: flushPasses), vdb_render's ray
        // termination (|T|^2 < cutoff), and the slab's accumulators cleared (lanes outside
        // x0..x1 hold zeros: nothing outside the dirty box was added).
        // Per lane only where something happens: the passes (Z only where the mean alpha crosses
        // 0.5 in this slab, flushPasses' test; every composited lane with extra passes or deep
        // samples) and the rays that stop (vdb_render's |T|^2 < cutoff, or cut inside the slab).
        const auto ends = hn::And(chosen, hn::Or(hn::Lt(hn::Load(d, cut), one), hn::Lt(hn::Mul(t2Now, hn::Set(d, float(3 / C))), hn::Set(d, mCutoff))));
        auto perLane = ends;
        if (passes) {
            const bool everyLane = mPassCount > 0 || mOptions.passes.deep;
            const auto crosses = hn::And(hn::And(hn::Gt(hn::Load(d, meanBefore), hn::Set(d, 0.5f)), hn::Le(meanOf(p), hn::Set(d, 0.5f))), hn::IsInf(hn::LoadU(d, &mZ[p])));
            perLane = hn::Or(perLane, hn::And(chosen, everyLane ? chosen : crosses));
        }
        if (!hn::AllFalse(d, perLane)) {
            alignas(64) float endsLanes[kLanes];
            hn::Store(hn::IfThenElseZero(perLane, one), d, lanes);
            hn::Store(hn::IfThenElseZero(ends, one), d, endsLanes);
            for (int i = 0; i < kLanes; ++i) {
                if (lanes[i] == 0.0f) continue;
                if (passes) {
                    float e[C], l[C], coloured[C];
                    for (int c = 0; c < C; ++c) {
                        mTBefore[c] = tBefore[c][i];
                        e[c] = emission[c][i];
                        l[c] = lit[c][i];
                        coloured[c] = litColoured[c][i];
                    }
                    if (cut[i] < 1.0f) keepFront(slab, p + i, cut[i]); // the passes' sources and depth
                    flushPasses(slab, p + i, meanBefore[i], e, l, coloured);
                }
                if (endsLanes[i] != 0.0f) terminate(p + i);
            }
        }
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + std::size_t(c) * kTilePixels + std::size_t(p);
            hn::StoreU(zero, d, &mTau[i]);
            if (!mEmission.empty()) hn::StoreU(zero, d, &mEmission[i]);
            if (!mScatter.empty()) hn::StoreU(zero, d, &mScatter[i]);
            for (int k = 0; k < mPassCount; ++k) hn::StoreU(zero, d, &mPassEmission[passIndex(slab, k, c) + std::size_t(p)]);
            for (int k = 0; k < (mLayerTau.empty() ? 0 : mLayers); ++k) hn::StoreU(zero, d, &mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]);
        }
        if (!mMoment.empty()) {
            hn::StoreU(zero, d, &mMoment[slot(slab) * kTilePixels + std::size_t(p)]);
            hn::StoreU(zero, d, &mMoment2[slot(slab) * kTilePixels + std::size_t(p)]);
        }
        if (!mShift.empty()) {
            for (std::size_t k = 0; k < shiftFloats(); k += kTilePixels) hn::StoreU(zero, d, &mShift[slot(slab) * shiftFloats() + k + std::size_t(p)]);
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
