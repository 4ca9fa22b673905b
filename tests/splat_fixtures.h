/// @file splat_fixtures.h
/// @brief Splats made by hand for the raster stage's tests (slab compositor, image levels).
#pragma once

#include "projection/projection.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vdb_ewa::test {

/// Append a round grey splat to @a set: centre (cx, cy), standard deviation @a sigma pixels, peak
/// optical depth @a tau, in @a slab alone, cut off at 3 sigma inside a @a width x @a height image.
inline void addRoundSplat(detail::SplatSet& set, float cx, float cy, double sigma, float tau, std::int64_t slab, int width, int height)
{
    detail::Splat s{};
    s.cx = cx;
    s.cy = cy;
    s.qa = s.qc = float(1.0 / (sigma * sigma));
    s.cutoff = 9.0f;
    const double h = 3.0 * sigma;
    s.x0 = std::max(0, int(std::ceil(cx - h - 0.5)));
    s.x1 = std::min(width - 1, int(std::floor(cx + h - 0.5)));
    s.y0 = std::max(0, int(std::ceil(cy - h - 0.5)));
    s.y1 = std::min(height - 1, int(std::floor(cy + h - 0.5)));
    for (int c = 0; c < 3; ++c) s.tau[c] = s.scatter[c] = s.emission[c] = tau;
    s.firstSlab = slab;
    s.slabCount = 1;
    s.shareOffset = set.shares.size();
    set.shares.push_back(1.0f);
    set.shareMoments.insert(set.shareMoments.end(), {0.5f, 0.3f});
    set.splats.push_back(s);
}

} // namespace vdb_ewa::test
