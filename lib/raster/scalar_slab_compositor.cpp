/// @file scalar_slab_compositor.cpp
/// @brief The slab compositor's scalar backend (raster/slab_compositor.h): the tile sweep
///        (tile_compositor-inl.h) with one pixel at a time in its two inner loops, the footprint
///        row and the slab flush. The test oracle of the SIMD backend.
#include "raster/slab_compositor.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace scalar_backend {

#include "raster/tile_compositor-inl.h"

/// Nothing carried between rows: each row steps along itself (addRow).
template <int C> struct TileCompositor<C>::RowSteps
{
};

template <int C> typename TileCompositor<C>::RowSteps TileCompositor<C>::startRows(const Splat&, int, int, int, int) const
{
    return {};
}

template <int C>
void TileCompositor<C>::addRow(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift, int y, int x0,
    int x1, float k, RowSteps&)
{
    const double qa = s.qa, qb = s.qb, qc = s.qc;
    const double dy = double(mY0 + y) + 0.5 - double(s.cy), dx0 = double(mX0 + x0) + 0.5 - double(s.cx);
    auto r = [&](double dx) { return qa * dx * dx + 2.0 * qb * dx * dy + qc * dy * dy; };
    const int n = x1 - x0 + 1, p0 = y * kTileSize + x0;
    float weights[kTileSize];
    // Very narrow footprints (qa > 16) would overflow the incremental factor: exact exp.
    const ExpEvaluation mode = (mExp == ExpEvaluation::Incremental && qa > 16.0) ? ExpEvaluation::Exact : mExp;
    switch (mode) {
    case ExpEvaluation::Incremental: {
        // r is quadratic in x: forward differencing in the exponential domain,
        // g(x+1) = g(x) m(x), m(x+1) = m(x) k with k = exp(-qa) (once per splat): the
        // paper's two additions per pixel turned into two multiplications.
        float g = std::exp(float(-0.5 * r(dx0)));
        float m = std::exp(float(-0.5 * (qa * (2.0 * dx0 + 1.0) + 2.0 * qb * dy)));
        for (int i = 0; i < n; ++i) {
            weights[i] = g;
            g *= m;
            m *= k;
        }
        break;
    }
    case ExpEvaluation::Exact:
        for (int i = 0; i < n; ++i) weights[i] = float(std::exp(-0.5 * r(dx0 + double(i))));
        break;
    case ExpEvaluation::Table:
        for (int i = 0; i < n; ++i) weights[i] = mTable->lookup(float(r(dx0 + double(i))));
        break;
    }
    if (mOptions.taperEdge > 0.0f) {
        for (int i = 0; i < n; ++i) weights[i] = std::max(weights[i] - mOptions.taperEdge, 0.0f);
    }
    // Spread the row into every slab the kernel overlaps: contiguous, vectorisable.
    forEachPlane(s, shares, moments, passSources, shift, p0, [&](float* plane, float factor) {
        for (int i = 0; i < n; ++i) plane[i] += weights[i] * factor;
    });
}

template <int C>
void TileCompositor<C>::flushRow(std::int64_t slab, int y, int x0, int x1)
{
    for (int x = x0; x <= x1; ++x) {
        flushPixel(slab, y * kTileSize + x);
        clearPixel(slab, y * kTileSize + x);
    }
}

} // namespace scalar_backend

std::unique_ptr<SlabCompositor> scalarSlabCompositor(int channels)
{
    if (channels == 1) return std::make_unique<scalar_backend::TileSweepCompositor<1>>();
    return std::make_unique<scalar_backend::TileSweepCompositor<3>>();
}

} // namespace detail
} // namespace vdb_ewa
