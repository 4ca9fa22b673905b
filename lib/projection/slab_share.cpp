/// @file slab_share.cpp
/// @brief Analytic per-slab shares of a Gaussian along the viewing ray (ewa-brief Sec. 5).
#include <vdb_ewa/slab_share.h>

#include <algorithm>
#include <cmath>

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
    double clipNear, double clipFar, std::int64_t& first, float* shares, int maxCount, float* moments)
{
    const std::int64_t span = slabSpan(slabs, mu, sd, truncation, clipNear, clipFar, first);
    if (span <= 0) return 0;
    double lo, hi;
    clippedDepthRange(mu, sd, truncation, clipNear, clipFar, lo, hi);
    const double mass = 2.0 * normalCdf(truncation) - 1.0;
    const double invSd = 1.0 / sd;
    const int count = int(std::min<std::int64_t>(span, maxCount));
    const auto pdf = [](double x) { return 0.39894228040143267794 * std::exp(-0.5 * x * x); };
    double z0 = lo, cdfLo = normalCdf((lo - mu) * invSd), pdfLo = pdf((lo - mu) * invSd);
    for (int i = 0; i < count; ++i) {
        const double z1 = std::min(slabs.start(first + i + 1), hi);
        const double cdfHi = normalCdf((z1 - mu) * invSd), pdfHi = moments ? pdf((z1 - mu) * invSd) : 0.0;
        const double p = cdfHi - cdfLo;
        shares[i] = float(p / mass);
        if (moments) {
            // The truncated normal's mean and variance; where too little mass lies in the slab
            // for the quotients to be accurate, a uniform layer over [z0, z1] instead.
            const double a = (z0 - mu) * invSd, b = (z1 - mu) * invSd;
            double mean = 0.5 * (z0 + z1), var = (z1 - z0) * (z1 - z0) / 12.0;
            if (p > 1e-9) {
                const double m = (pdfLo - pdfHi) / p;
                mean = mu + sd * m;
                var = sd * sd * std::max(0.0, 1.0 + (a * pdfLo - b * pdfHi) / p - m * m);
            }
            const double u = std::clamp((mean - slabs.start(first + i)) / slabs.thickness, 0.0, 1.0);
            moments[2 * i] = float(u);
            moments[2 * i + 1] = float(std::clamp(u * u + var / (slabs.thickness * slabs.thickness), 0.0, 1.0));
        }
        z0 = z1;
        cdfLo = cdfHi;
        pdfLo = pdfHi;
    }
    return count;
}

} // namespace vdb_ewa
