/// @file slab_share.cpp
/// @brief Analytic per-slab shares of a Gaussian along the viewing ray (ewa-brief Sec. 5).
#include <vdb_ewa/slab_share.h>

#include <algorithm>

namespace vdb_ewa {

std::int64_t slabSpan(const SlabGrid& slabs, double mu, double sd, double truncation,
    double clipNear, double clipFar, std::int64_t& first)
{
    double lo, hi;
    if (!clippedDepthRange(mu, sd, truncation, clipNear, clipFar, lo, hi)) return 0;
    first = slabs.index(lo);
    return slabs.index(hi) - first + 1;
}

int slabShares(const SlabGrid& slabs, double mu, double sd, double truncation,
    double clipNear, double clipFar, std::int64_t& first, float* shares, int maxCount)
{
    const std::int64_t span = slabSpan(slabs, mu, sd, truncation, clipNear, clipFar, first);
    if (span <= 0) return 0;
    double lo, hi;
    clippedDepthRange(mu, sd, truncation, clipNear, clipFar, lo, hi);
    const double mass = 2.0 * normalCdf(truncation) - 1.0;
    const double invSd = 1.0 / sd;
    const int count = int(std::min<std::int64_t>(span, maxCount));
    double cdfLo = normalCdf((lo - mu) * invSd);
    for (int i = 0; i < count; ++i) {
        const double z1 = std::min(slabs.start(first + i + 1), hi);
        const double cdfHi = normalCdf((z1 - mu) * invSd);
        shares[i] = float((cdfHi - cdfLo) / mass);
        cdfLo = cdfHi;
    }
    return count;
}

} // namespace vdb_ewa
