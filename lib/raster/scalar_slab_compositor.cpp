/// @file scalar_slab_compositor.cpp
/// @brief The slab compositor's scalar backend (raster/slab_compositor.h): the tile sweep
///        (tile_compositor-inl.h) with one pixel at a time in its two inner loops, the footprint
///        row and the slab flush. The test oracle of the SIMD backend.
#include "raster/slab_compositor.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace scalar_backend {

#include "raster/tile_compositor-inl.h"

template <int C>
void TileCompositor<C>::rowWeights(double qa, double qb, double qc, double dx0, double dy, int n, float k, int p0, float* out) const
{
    auto r = [&](double dx) { return qa * dx * dx + 2.0 * qb * dx * dy + qc * dy * dy; };
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
            out[i] = g;
            g *= m;
            m *= k;
        }
        break;
    }
    case ExpEvaluation::Exact:
        for (int i = 0; i < n; ++i) out[i] = float(std::exp(-0.5 * r(dx0 + double(i))));
        break;
    case ExpEvaluation::Table:
        for (int i = 0; i < n; ++i) out[i] = mTable->lookup(float(r(dx0 + double(i))));
        break;
    }
    for (int i = 0; i < n; ++i) {
        if (!mAlive[p0 + i]) out[i] = 0.0f;
    }
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
