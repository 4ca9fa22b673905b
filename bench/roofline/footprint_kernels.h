/// @file footprint_kernels.h
/// @brief The volume rasteriser's inner loop, isolated for the roofline benchmark: a splat's
///        footprint weights exp(-r/2) over its row spans in a 16x16 tile, spread into one slab
///        accumulator (optical depth and the two position moments: lib/raster/scalar_slab_compositor.cpp,
///        TileCompositor::add), and a slab's front-to-back composite per pixel (flush).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace roofline {

constexpr int kTile = 16;
constexpr int kPixels = kTile * kTile;

/// A splat's screen footprint: centre and conic in tile pixels (d^T Q d < cutoff).
struct Footprint
{
    float cx, cy, qa, qb, qc, cutoff;
    float tau, w1, w2; ///< the slab share's optical depth and position moments (x tau)
};

/// The pixels x0..x1 of tile row @a y inside the footprint's ellipse d^T Q d < cutoff (its
/// row span, solved for dx); false if none. @a dy: the row's offset from the centre.
inline bool rowSpan(const Footprint& s, int y, float& dy, int& x0, int& x1)
{
    const float invQa = 1.0f / s.qa, detQ = s.qa * s.qc - s.qb * s.qb;
    dy = float(y) + 0.5f - s.cy;
    const float disc = s.qa * s.cutoff - detQ * dy * dy;
    if (!(disc > 0.0f)) return false;
    const float half = std::sqrt(disc) * invQa;
    const float xc = s.cx - 0.5f - s.qb * dy * invQa;
    x0 = std::max(0, int(std::ceil(xc - half)));
    x1 = std::min(kTile - 1, int(std::floor(xc + half)));
    return x0 <= x1;
}

/// A slab's accumulators and a pixel's state, one float per tile pixel each.
struct Accumulators
{
    float tau[kPixels], m1[kPixels], m2[kPixels];
    float emission[kPixels], colour[kPixels], transmittance[kPixels];
};

/// Spread every footprint into @a acc; returns the footprint samples (pixels inside a cut-off).
std::size_t splatScalar(const std::vector<Footprint>& splats, Accumulators& acc);
/// Composite the slab in @a acc into the pixels' colour and transmittance (1 - exp(-tau) per
/// pixel); returns the pixels composited.
std::size_t compositeScalar(Accumulators& acc);

/// The same with 8 floats a vector (AVX2 and FMA; call only where the CPU has them).
std::size_t splatAvx2(const std::vector<Footprint>& splats, Accumulators& acc);
std::size_t compositeAvx2(Accumulators& acc);

/// The same with Highway (footprint_hwy.cpp): compiled
/// for AVX2, SSE4 and a portable fallback, the best the CPU has picked at run time.
std::size_t splatHwy(const std::vector<Footprint>& splats, Accumulators& acc);
std::size_t compositeHwy(Accumulators& acc);
/// The name of the target HWY_DYNAMIC_DISPATCH picks on this CPU ("AVX2", "SSE4", ...).
const char* hwyTarget();

} // namespace roofline
