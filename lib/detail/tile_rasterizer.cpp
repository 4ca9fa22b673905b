/// @file tile_rasterizer.cpp
#include "tile_rasterizer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr int kTilePixels = kTileSize * kTileSize;

/// Screen tiles and the splats that overlap each (indices into SplatSet::splats).
struct TileBins
{
    int tilesX = 0, tilesY = 0;
    std::vector<std::uint64_t> offsets; ///< tilesX * tilesY + 1
    std::vector<std::uint32_t> indices;
};

TileBins binSplats(const std::vector<Splat>& splats, int width, int height)
{
    TileBins bins;
    bins.tilesX = (width + kTileSize - 1) / kTileSize;
    bins.tilesY = (height + kTileSize - 1) / kTileSize;
    const std::size_t tiles = std::size_t(bins.tilesX) * bins.tilesY;
    bins.offsets.assign(tiles + 1, 0);
    for (const Splat& s : splats) {
        for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
            for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) ++bins.offsets[std::size_t(ty) * bins.tilesX + tx + 1];
    }
    for (std::size_t t = 0; t < tiles; ++t) bins.offsets[t + 1] += bins.offsets[t];
    bins.indices.resize(bins.offsets.back());
    std::vector<std::uint64_t> cursor(bins.offsets.begin(), bins.offsets.end() - 1);
    for (std::uint32_t i = 0; i < splats.size(); ++i) {
        const Splat& s = splats[i];
        for (int ty = s.y0 / kTileSize; ty <= s.y1 / kTileSize; ++ty)
            for (int tx = s.x0 / kTileSize; tx <= s.x1 / kTileSize; ++tx) bins.indices[cursor[std::size_t(ty) * bins.tilesX + tx]++] = i;
    }
    return bins;
}

/// exp(-r/2) for r in [0, rMax] in a 1D table, linearly interpolated (Sec. 7.1).
class ExpTable
{
public:
    explicit ExpTable(float rMax) : mScale(float(kSize - 1) / rMax)
    {
        for (int i = 0; i < kSize; ++i) mValues[i] = std::exp(-0.5f * float(i) / mScale);
        mValues[kSize] = mValues[kSize - 1];
    }
    float lookup(float r) const
    {
        const float x = std::min(r * mScale, float(kSize - 1));
        const int i = int(x);
        return mValues[i] + (x - float(i)) * (mValues[i + 1] - mValues[i]);
    }

private:
    static constexpr int kSize = 1024;
    float mScale;
    float mValues[kSize + 1];
};

/// The slab sweep of one screen tile: a ring of slab accumulators (optical depth and
/// emission per channel and pixel), flushed front to back with the exact update.
/// @tparam C colour channels carried: 3, or 1 when every splat is grey (tau and emission the
///           same in R, G and B, as with vdb_render's default model): the same arithmetic per
///           channel, so the image is bit-identical, at a third of the work.
template <int C>
class TileCompositor
{
public:
    TileCompositor(int x0, int y0, int w, int h, int ringSize, float cutoff, ExpEvaluation exp, const ExpTable* table)
        : mX0(x0), mY0(y0), mW(w), mH(h), mMask(ringSize - 1), mCutoff(cutoff), mExp(exp), mTable(table),
          mTau(std::size_t(ringSize) * C * kTilePixels, 0.0f),
          mEmission(std::size_t(ringSize) * C * kTilePixels, 0.0f),
          mDirty(std::size_t(ringSize))
    {
        std::fill(std::begin(mT), std::end(mT), 1.0f);
        std::fill(std::begin(mC), std::end(mC), 0.0f);
        std::fill(std::begin(mAlive), std::end(mAlive), 0);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) mAlive[y * kTileSize + x] = 1;
        mAliveCount = w * h;
    }

    bool opaque() const { return mAliveCount == 0; }

    /// exp(-r/2) along a row, r = qa dx^2 + 2 qb dx dy + qc dy^2, dx = dx0, dx0 + 1, ...
    void rowWeights(double qa, double qb, double qc, double dx0, double dy, int n, float k, float* out) const
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
    }

    void add(const Splat& s, const float* shares)
    {
        // Slabs in front of this splat's first one can receive nothing more: flush them.
        flushBefore(s.firstSlab);
        const int lx0 = std::max(s.x0 - mX0, 0), lx1 = std::min(s.x1 - mX0, mW - 1);
        const int ly0 = std::max(s.y0 - mY0, 0), ly1 = std::min(s.y1 - mY0, mH - 1);
        if (lx0 > lx1 || ly0 > ly1) return;
        const int count = int(s.slabCount);
        for (int k = 0; k < count; ++k) markDirty(s.firstSlab + k, lx0, ly0, lx1, ly1);
        const float kx = float(std::exp(-double(s.qa)));
        // Row spans of the ellipse d^T Q d < cutoff (Sec. 7.1), solved for dx in float with
        // det Q formed in double (no cancellation), once per splat.
        const float invQa = float(1.0 / double(s.qa));
        const float detQ = float(double(s.qa) * double(s.qc) - double(s.qb) * double(s.qb));
        const float qaCutoff = float(double(s.qa) * double(s.cutoff));
        const double qa = s.qa, qb = s.qb, qc = s.qc;
        for (int ly = ly0; ly <= ly1; ++ly) {
            const float dyf = float(mY0 + ly) + 0.5f - s.cy;
            const float disc = qaCutoff - detQ * dyf * dyf;
            if (!(disc > 0.0f)) continue;
            const float half = std::sqrt(disc) * invQa;
            const float xc = s.cx - 0.5f - s.qb * dyf * invQa;
            // Clamped to the tile before the conversion to int (huge footprints).
            const float xFirst = std::max(xc - half, float(mX0 + lx0) - 1.0f);
            const float xLast = std::min(xc + half, float(mX0 + lx1) + 1.0f);
            const int lxa = std::max(lx0, int(std::ceil(xFirst)) - mX0);
            const int lxb = std::min(lx1, int(std::floor(xLast)) - mX0);
            if (lxa > lxb) continue;
            const double dy = double(mY0 + ly) + 0.5 - double(s.cy);
            // The row's footprint values exp(-r/2), 0 for terminated pixels.
            float weights[kTileSize];
            const int n = lxb - lxa + 1;
            const int p0 = ly * kTileSize + lxa;
            const double dx0 = double(mX0 + lxa) + 0.5 - double(s.cx);
            rowWeights(qa, qb, qc, dx0, dy, n, kx, weights);
            for (int i = 0; i < n; ++i) {
                if (!mAlive[p0 + i]) weights[i] = 0.0f;
            }
            // Spread the row into every slab the kernel overlaps: contiguous, vectorisable.
            for (int j = 0; j < count; ++j) {
                const std::size_t base = slot(s.firstSlab + j) * C * kTilePixels + std::size_t(p0);
                for (int c = 0; c < C; ++c) {
                    const float wt = shares[j] * s.tau[c], we = shares[j] * s.emission[c];
                    float* tau = &mTau[base + std::size_t(c) * kTilePixels];
                    float* em = &mEmission[base + std::size_t(c) * kTilePixels];
                    for (int i = 0; i < n; ++i) {
                        tau[i] += weights[i] * wt;
                        em[i] += weights[i] * we;
                    }
                }
            }
        }
    }

    /// Flush every pending slab and write the tile's pixels.
    void finish(Image& image)
    {
        flushBefore(std::numeric_limits<std::int64_t>::max());
        for (int ly = 0; ly < mH; ++ly)
            for (int lx = 0; lx < mW; ++lx) {
                const int p = ly * kTileSize + lx;
                float* px = image.pixel(mX0 + lx, mY0 + ly);
                if (C == 1) {
                    const float t = mT[p];
                    px[0] = px[1] = px[2] = mC[p];
                    px[3] = 1.0f - (t + t + t) / 3.0f; // the three-channel mean's rounding, bit for bit
                    continue;
                }
                for (int c = 0; c < 3; ++c) px[c] = mC[c * kTilePixels + p];
                px[3] = 1.0f - (mT[p] + mT[kTilePixels + p] + mT[2 * kTilePixels + p]) / 3.0f;
            }
    }

private:
    struct Dirty
    {
        bool on = false;
        std::int64_t slab = 0;
        int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    };

    std::size_t slot(std::int64_t slab) const { return std::size_t(slab & mMask); }

    void markDirty(std::int64_t slab, int x0, int y0, int x1, int y1)
    {
        Dirty& d = mDirty[slot(slab)];
        if (!d.on) {
            d = {true, slab, x0, y0, x1, y1};
            mPending.push_back(slab);
            return;
        }
        d.x0 = std::min(d.x0, x0);
        d.y0 = std::min(d.y0, y0);
        d.x1 = std::max(d.x1, x1);
        d.y1 = std::max(d.y1, y1);
    }

    /// Composite, in depth order, every pending slab in front of @a slab.
    void flushBefore(std::int64_t slab)
    {
        if (mPending.empty() || mPending.front() >= slab) return;
        std::sort(mPending.begin(), mPending.end());
        std::size_t n = 0;
        while (n < mPending.size() && mPending[n] < slab) flush(mPending[n++]);
        mPending.erase(mPending.begin(), mPending.begin() + std::ptrdiff_t(n));
    }

    void flush(std::int64_t slab)
    {
        Dirty& d = mDirty[slot(slab)];
        const std::size_t base = slot(slab) * C * kTilePixels;
        for (int ly = d.y0; ly <= d.y1; ++ly)
            for (int lx = d.x0; lx <= d.x1; ++lx) {
                const int p = ly * kTileSize + lx;
                if (mAlive[p]) {
                    float t2 = 0.0f; // |T|^2 over R, G, B
                    for (int c = 0; c < C; ++c) {
                        const std::size_t i = base + c * kTilePixels + std::size_t(p);
                        float& t = mT[c * kTilePixels + p];
                        compositeSlab(mTau[i], mEmission[i], mC[c * kTilePixels + p], t);
                        t2 += t * t;
                    }
                    // vdb_render's ray termination: |T|^2 < cutoff (early termination, Sec. 5).
                    if (t2 * float(3 / C) < mCutoff) {
                        mAlive[p] = 0;
                        --mAliveCount;
                    }
                }
                for (int c = 0; c < C; ++c) {
                    const std::size_t i = base + c * kTilePixels + std::size_t(p);
                    mTau[i] = 0.0f;
                    mEmission[i] = 0.0f;
                }
            }
        d.on = false;
    }

    int mX0, mY0, mW, mH;
    std::int64_t mMask;
    float mCutoff;
    ExpEvaluation mExp;
    const ExpTable* mTable;
    std::vector<float> mTau, mEmission; ///< [slot][channel][pixel]
    std::vector<Dirty> mDirty;
    std::vector<std::int64_t> mPending; ///< slabs holding contributions, not yet composited
    float mT[C * kTilePixels];
    float mC[C * kTilePixels];
    std::uint8_t mAlive[kTilePixels];
    int mAliveCount = 0;
};

int ringSizeFor(std::uint32_t maxSpan)
{
    int r = 1;
    while (r < int(maxSpan) + 1) r *= 2;
    return r;
}

/// Splats whose optical depth and emission are the same in R, G and B.
bool allGrey(const std::vector<Splat>& splats)
{
    return std::all_of(splats.begin(), splats.end(), [](const Splat& s) {
        return s.tau[0] == s.tau[1] && s.tau[0] == s.tau[2] && s.emission[0] == s.emission[1] &&
               s.emission[0] == s.emission[2];
    });
}

/// Composite every tile with a C-channel compositor.
template <int C>
void compositeTiles(const SplatSet& set, const TileBins& bins, int width, int height, const RenderSettings& settings,
    Image& image, std::vector<std::uint64_t>& skipped)
{
    const float cutoff = float(settings.cutoff);
    const int tiles = bins.tilesX * bins.tilesY;
    const ExpTable table(float(settings.cutoffRadius * settings.cutoffRadius));
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        std::vector<std::uint32_t> order;
        for (int t = range.begin(); t < range.end(); ++t) {
            const int tx = t % bins.tilesX, ty = t / bins.tilesX;
            const int x0 = tx * kTileSize, y0 = ty * kTileSize;
            const int w = std::min(kTileSize, width - x0), h = std::min(kTileSize, height - y0);
            order.assign(bins.indices.begin() + std::ptrdiff_t(bins.offsets[t]),
                bins.indices.begin() + std::ptrdiff_t(bins.offsets[t + 1]));
            // Indices arrive in kernel order; a stable sort by first slab keeps ties in it.
            std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
                return set.splats[a].firstSlab < set.splats[b].firstSlab;
            });
            std::uint32_t maxSpan = 1;
            for (std::uint32_t i : order) maxSpan = std::max(maxSpan, set.splats[i].slabCount);
            TileCompositor<C> tile(x0, y0, w, h, ringSizeFor(maxSpan), cutoff, settings.expEvaluation, &table);
            std::size_t done = 0;
            for (; done < order.size() && !tile.opaque(); ++done) {
                const Splat& s = set.splats[order[done]];
                tile.add(s, set.shares.data() + s.shareOffset);
            }
            skipped[std::size_t(t)] = order.size() - done;
            tile.finish(image);
        }
    });
}

} // namespace

Image rasterizeSplats(const SplatSet& set, int width, int height, const RenderSettings& settings,
    RasterStats& stats)
{
    Image image(width, height);
    const TileBins bins = binSplats(set.splats, width, height);
    stats.splatTilePairs = bins.indices.size();
    const int tiles = bins.tilesX * bins.tilesY;
    std::vector<std::uint64_t> skipped(std::size_t(tiles), 0);
    if (allGrey(set.splats)) compositeTiles<1>(set, bins, width, height, settings, image, skipped);
    else compositeTiles<3>(set, bins, width, height, settings, image, skipped);
    stats.tiles = std::uint64_t(tiles);
    for (std::uint64_t n : skipped) {
        stats.tilesOpaque += (n > 0);
        stats.pairsSkipped += n;
    }
    return image;
}

} // namespace detail
} // namespace vdb_ewa
