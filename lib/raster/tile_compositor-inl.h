/// @file tile_compositor-inl.h
/// @brief The slab sweep of one screen tile, shared by the slab compositor's backends
///        (raster/slab_compositor.h): a ring of slab accumulators filled splat by splat
///        (Sec. 7.1's footprint evaluation) and flushed front to back with the exact update, lit
///        per slab sample.
///
/// Included inside a backend's own namespace, once per instruction set: scalar_slab_compositor.cpp
/// once, simd_slab_compositor.cpp once per Highway target. So every instantiation is compiled for
/// its target and none is shared between targets (no ODR clash between, say, an AVX2 and a
/// baseline copy of one inline function). Hence no include guard and no includes: the including
/// file includes raster/slab_compositor.h, <tbb/enumerable_thread_specific.h>, <tbb/parallel_for.h>,
/// <algorithm>, <array>, <cmath>
/// and <limits> first, outside its namespace. A backend defines TileCompositor<C>'s two inner
/// loops, addRow and flushRow; the scalar ones are the others' test oracle.

/// The slab sweep of one screen tile: a ring of slab accumulators (optical depth, emission
/// and the passes' source terms per channel and pixel), flushed front to back with the exact
/// update; the flush also finds Z and emits deep samples when asked.
/// @tparam C colour channels carried: 3, or 1 when every splat is grey (tau and emission the
///           same in R, G and B, as with vdb_render's default model): the same arithmetic per
///           channel, so the image is bit-identical, at a third of the work.
template <int C>
class TileCompositor
{
public:
    /// Pixel rays in one light's map coordinates, base + z dir (z: the slab coordinate), x, y,
    /// z apart.
    struct LightRays
    {
        double base[3][kTilePixels], dir[3][kTilePixels];
    };
    /// A slab's pixels holding contributions, and which slab.
    struct Dirty
    {
        bool on = false;
        std::int64_t slab = 0;
        int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    };
    /// A ring's storage between tiles (TileSweepStream lends it from tile to tile): every
    /// accumulator 0, every slot clean; the light rays' storage, traced again by the next tile
    /// (a fresh mapping of theirs costs more than tracing them).
    struct Ring
    {
        int size = 0;
        std::vector<float> tau, emission, scatter, passEmission, moment, moment2, shift, layerTau;
        std::vector<Dirty> dirty;
        std::vector<LightRays> rays;
        /// The coarser image levels' rings (imageLod), level k at k - 1 (lent with the tile's).
        std::vector<Ring> levels;
    };

    /// @a ringSize: slab accumulators in the ring, a power of two above the largest span of the
    /// splats to come (0: none yet; ensureRing allocates them).
    TileCompositor(int x0, int y0, int w, int h, int ringSize, const CompositeOptions& options)
        : mX0(x0), mY0(y0), mW(w), mH(h), mOriginX(x0), mOriginY(y0), mCutoff(options.cutoff), mExp(options.exp),
          mTable(options.table), mOptions(options), mPassCount(options.layout.count), mLayers(std::max(options.layers, 1)),
          mPassC(std::size_t(mPassCount) * C * kTilePixels, 0.0f)
    {
        ensureRing(ringSize);
        clearSamples();
        if (options.surface) {
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const std::size_t i = frameIndex(y * kTileSize + x);
                    mSurfacePending[y * kTileSize + x] = options.surface->rgba[4 * i + 3] > 0.0f && std::isfinite(options.surfaceAt[i]);
                }
        }
    }

    /// Every pixel's ray has stopped (at a coarser level: every sample's, so every pixel's
    /// interpolated |T|^2 is below the cutoff too).
    bool opaque() const { return mCompositeLevel > 0 ? mLevels[std::size_t(mCompositeLevel - 1)]->mAliveCount == 0 : mAliveCount == 0; }

    /// Image-space level of detail, compositing at a level (CompositeOptions::imageLodComposite):
    /// before the tile's first splat, the level it is composited at: the coarsest that each of
    /// the @a count splats @a order lists (the first window's, in a streamed frame) is
    /// accumulated at (levelOf), 0 (the pixels) where the frame cannot be composited at a
    /// level. A later, narrower splat takes the tile to its pixels (leaveLevel).
    void planLevel(const SplatSet& set, const std::uint32_t* order, std::size_t count)
    {
        if (mCompositeLevel >= 0 || count == 0) return;
        const bool composable = mOptions.imageLodComposite && mOptions.imageLod > 0.0f && !mOptions.surface && !mOptions.passes.deep && mLayers == 1;
        int level = composable ? kImageLevels - 1 : 0;
        for (std::size_t i = 0; i < count && level > 0; ++i) level = std::min(level, levelOf(set.splats[order[i]]));
        mCompositeLevel = level;
        if (level > 0) levelFor(level); // (the tile has its ring: ensureRing)
    }

    /// Give the tile a ring of at least @a ringSize slots (a power of two): @a spare's if it is
    /// large enough (a ring lent by a parked tile), else a new one; the pending slabs' planes,
    /// in the ring or spilled by park(), are put in their slots (streamed frames: a later
    /// window's splats may span more slabs than the earlier ones').
    void ensureRing(int ringSize, Ring* spare = nullptr)
    {
        ensureOwnRing(ringSize, spare);
        // Composited at a coarser level: that level's ring too, its spilled slabs in their slots.
        if (mCompositeLevel > 0) levelFor(mCompositeLevel);
    }

    /// Composite every pending slab in front of @a slab: no splat to come reaches one.
    void flushUpTo(std::int64_t slab)
    {
        if (mCompositeLevel > 0) {
            mLevels[std::size_t(mCompositeLevel - 1)]->flushUpTo(slab);
            return;
        }
        if (!mRaysTraced && !mPending.empty() && mPending.front() < slab) traceRays(); // a parked tile's rays went
        flushBefore(slab);
    }

    /// The first slab holding contributions not yet composited (none: the largest slab).
    std::int64_t firstPending() const
    {
        if (mCompositeLevel > 0) return mLevels[std::size_t(mCompositeLevel - 1)]->firstPending();
        return mPending.empty() ? std::numeric_limits<std::int64_t>::max() : mPending.front(); // kept in order (flushBefore)
    }

    /// Some slab holds contributions not yet composited.
    bool pending() const { return mCompositeLevel > 0 ? mLevels[std::size_t(mCompositeLevel - 1)]->pending() : !mPending.empty(); }

private:
    /// ensureRing's: the tile's own ring.
    void ensureOwnRing(int ringSize, Ring* spare)
    {
        ringSize = std::max(ringSize, mSpilledRing);
        if (ringSize <= mRingSize) return;
        if (mRingSize > 0) park(nullptr); // the pending slabs spilled, the small ring let go
        if (spare && spare->size >= ringSize) {
            ringSize = spare->size;
            mTau = std::move(spare->tau);
            mEmission = std::move(spare->emission);
            mScatter = std::move(spare->scatter);
            mPassEmission = std::move(spare->passEmission);
            mMoment = std::move(spare->moment);
            mMoment2 = std::move(spare->moment2);
            mShift = std::move(spare->shift);
            mLayerTau = std::move(spare->layerTau);
            mDirty = std::move(spare->dirty);
            mRays = std::move(spare->rays);
            mLevelSpares = std::move(spare->levels);
            spare->levels.clear();
            spare->size = 0;
        } else {
            TileCompositor fresh(*this, ringSize);
            mTau = std::move(fresh.mTau);
            mEmission = std::move(fresh.mEmission);
            mScatter = std::move(fresh.mScatter);
            mPassEmission = std::move(fresh.mPassEmission);
            mMoment = std::move(fresh.mMoment);
            mMoment2 = std::move(fresh.mMoment2);
            mShift = std::move(fresh.mShift);
            mLayerTau = std::move(fresh.mLayerTau);
            mDirty = std::move(fresh.mDirty);
        }
        mRingSize = ringSize;
        mMask = ringSize - 1;
        // The spilled slabs back in their slots, in pending order.
        std::size_t at = 0;
        for (std::size_t i = 0; i < mPending.size(); ++i) {
            const std::size_t to = slot(mPending[i]);
            forEachSlotPlane([&](std::vector<float>& plane, std::size_t floats) {
                std::copy_n(mSpill.begin() + std::ptrdiff_t(at), floats, plane.begin() + std::ptrdiff_t(to * floats));
                at += floats;
            });
            mDirty[to] = mSpilledDirty[i];
        }
        mSpill.clear(); // its storage kept: the next window spills about as much
        mSpilledDirty.clear();
        mSpilledRing = 0;
    }

public:
    /// Let the ring and the light rays go until the next splat (a streamed frame keeps its
    /// tiles between windows; a parked tile holds its pixels and the planes of its pending
    /// slabs, spilled; an opaque one its pixels only). @a spare (if given, and empty):
    /// receives the ring's storage, every slot cleared, instead of the allocator.
    void park(Ring* spare = nullptr)
    {
        if (mRingSize == 0) return;
        // The coarser levels' slabs reconstructed into the tile's first: spilled with them.
        for (const std::int64_t slab : mPending) foldLevels(slab, mDirty[slot(slab)]);
        parkLevels(spare && spare->size == 0 ? spare : nullptr);
        // An opaque tile's pending slabs can change nothing (every pixel has stopped): dropped.
        const bool keep = !opaque();
        mSpilledDirty.clear();
        for (const std::int64_t slab : mPending) {
            const std::size_t from = slot(slab);
            forEachSlotPlane([&](std::vector<float>& plane, std::size_t floats) {
                const auto first = plane.begin() + std::ptrdiff_t(from * floats);
                if (keep) mSpill.insert(mSpill.end(), first, first + std::ptrdiff_t(floats));
                std::fill_n(first, floats, 0.0f);
            });
            if (keep) mSpilledDirty.push_back(mDirty[from]);
            mDirty[from] = Dirty{};
        }
        if (!keep) mPending.clear();
        mSpilledRing = mPending.empty() ? 0 : mRingSize;
        if (spare && spare->size == 0) {
            spare->tau = std::move(mTau);
            spare->emission = std::move(mEmission);
            spare->scatter = std::move(mScatter);
            spare->passEmission = std::move(mPassEmission);
            spare->moment = std::move(mMoment);
            spare->moment2 = std::move(mMoment2);
            spare->shift = std::move(mShift);
            spare->layerTau = std::move(mLayerTau);
            spare->dirty = std::move(mDirty);
            spare->rays = std::move(mRays);
            spare->size = mRingSize;
        }
        for (std::vector<float>* ring : {&mTau, &mEmission, &mScatter, &mPassEmission, &mMoment, &mMoment2, &mShift, &mLayerTau}) *ring = {};
        mDirty = {};
        mRays = {};
        mRaysTraced = false;
        mRingSize = 0;
        mMask = -1;
    }

    /// The tile's counters, with @a skipped pairs skipped: the footprint weights evaluated
    /// (samples inside a cut-off, each spread into every slab its kernel overlaps), per image
    /// level, and the (pixel, slab) samples composited: the work the roofline benchmark's rates
    /// are measured in (bench/roofline).
    TileCounters counters(std::uint64_t skipped) const
    {
        TileCounters c{skipped, 0, mComposites, {}, {}};
        c.levelComposites[0] = mComposites;
        for (int k = 0; k < kImageLevels; ++k) {
            c.levelSamples[k] = mLevelSamples[k];
            c.samples += mLevelSamples[k];
            if (k == 0 || !mLevels[std::size_t(k - 1)]) continue;
            c.levelComposites[k] = mLevels[std::size_t(k - 1)]->mComposites;
            c.composites += c.levelComposites[k];
        }
        return c;
    }

    /// What a backend carries from one footprint row to the next (the SIMD one: the weights
    /// stepped down the rows), made for splat @a s's rows ly0..ly1, columns lx0..lx1 of the
    /// tile. Defined by each backend.
    struct RowSteps;
    RowSteps startRows(const Splat& s, int lx0, int ly0, int lx1, int ly1) const;

    /// Add splat @a s's footprint values exp(-r/2) (Sec. 7.1, r = d^T Q d) on tile row @a y, pixels
    /// x0..x1 (inside its cut-off ellipse, cut to the row's live pixels), to every slab it
    /// overlaps (forEachPlane); what terminated pixels inside the span receive is never
    /// composited. @a k: exp(-qa), for a backend that steps
    /// along the row. Defined by each backend.
    void addRow(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift, int y, int x0,
        int x1, float k, RowSteps& steps);

    /// @a passSources: the splat's extra source terms (mPassCount x RGB), or null if none.
    /// @a moments: the position moments of each share in its slab (SplatSet::shareMoments).
    /// @a shift: its move from its material's place in the still field (SplatSet::shifts), or
    /// null (it stood still).
    void add(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift)
    {
        if (mCompositeLevel > 0) {
            if (levelOf(s) >= mCompositeLevel) {
                addAtLevel(s, shares, moments, passSources, shift);
                return;
            }
            leaveLevel(); // a narrower footprint: the pixels from here on
        }
        if (!mRaysTraced) traceRays();
        // Slabs in front of this splat's first one can receive nothing more: flush them.
        flushBefore(s.firstSlab);
        if (s.layerCount != 0 && !mLayerTau.empty() && mLayerT.empty()) splitLayers();
        const int lx0 = std::max(s.x0 - mX0, 0), lx1 = std::min(s.x1 - mX0, mW - 1);
        const int ly0 = std::max(s.y0 - mY0, 0), ly1 = std::min(s.y1 - mY0, mH - 1);
        if (lx0 > lx1 || ly0 > ly1) return;
        for (int k = 0; k < int(s.slabCount); ++k) markDirty(s.firstSlab + k, lx0, ly0, lx1, ly1);
        const int level = levelOf(s);
        if (level == 0) {
            mLevelSamples[0] += accumulate(s, shares, moments, passSources, shift, lx0, ly0, lx1, ly1);
            return;
        }
        // Image-space level of detail: at the level's samples, reconstructed onto the pixels
        // when the slab is composited (foldLevels).
        accumulateAtLevel(levelFor(level), level, s, shares, moments, passSources, shift);
    }

    /// Add @a s's footprint (add's) at the tile's samples (lx0..lx1, ly0..ly1) inside its
    /// cut-off ellipse; the number of samples added.
    std::uint64_t accumulate(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift,
        int lx0, int ly0, int lx1, int ly1)
    {
        std::uint64_t samples = 0;
        const float kx = float(std::exp(-double(s.qa)));
        // Row spans of the ellipse d^T Q d < cutoff (Sec. 7.1), solved for dx in float with
        // det Q formed in double (no cancellation), once per splat.
        const float invQa = float(1.0 / double(s.qa));
        const float detQ = float(double(s.qa) * double(s.qc) - double(s.qb) * double(s.qb));
        const float qaCutoff = float(double(s.qa) * double(s.cutoff));
        RowSteps steps = startRows(s, lx0, ly0, lx1, ly1);
        for (int ly = ly0; ly <= ly1; ++ly) {
            const float dyf = float(mY0 + ly) + 0.5f - s.cy;
            const float disc = qaCutoff - detQ * dyf * dyf;
            if (!(disc > 0.0f)) continue;
            const float half = std::sqrt(disc) * invQa;
            const float xc = s.cx - 0.5f - s.qb * dyf * invQa;
            // Clamped to the tile before the conversion to int (huge footprints).
            const float xFirst = std::max(xc - half, float(mX0 + lx0) - 1.0f);
            const float xLast = std::min(xc + half, float(mX0 + lx1) + 1.0f);
            // Terminated pixels at either end of the row never composite again: skipped.
            const int lxa = std::max({lx0, int(std::ceil(xFirst)) - mX0, mRowFirst[ly]});
            const int lxb = std::min({lx1, int(std::floor(xLast)) - mX0, mRowLast[ly]});
            if (lxa > lxb) continue;
            addRow(s, shares, moments, passSources, shift, ly, lxa, lxb, kx, steps);
            samples += std::uint64_t(lxb - lxa + 1);
        }
        return samples;
    }

    /// Every accumulator plane a splat's row feeds and its factor, for @a add(plane, factor):
    /// the row's footprint values x factor are added to plane[p], plane[p + 1], ... (p: the
    /// tile pixel @a p). Per slab the kernel overlaps: the position moments (lit frames) and
    /// the shift's (moving ones), then per channel the optical depth, emission, scattering
    /// weight and the passes' sources.
    /// Always inlined into a backend's addRow (the shutter layers' branch would tip the
    /// compiler's budget, and the row's adds would become calls).
    template <typename Add>
    [[gnu::always_inline]] inline void forEachPlane(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift, int p, Add&& add)
    {
        // Motion blur's shutter layers: the layers a piece of a path is on, [layerFirst,
        // layerLast) (a splat on every layer: none of its own).
        const bool layered = s.layerCount != 0 && !mLayerTau.empty();
        const int layerFirst = layered ? std::min(int(s.layerFirst), mLayers - 1) : 0;
        const int layerLast = layered ? std::min(layerFirst + int(s.layerCount), mLayers) : 0;
        for (int j = 0; j < int(s.slabCount); ++j) {
            const std::size_t base = slot(s.firstSlab + j) * C * kTilePixels + std::size_t(p);
            if (!mMoment.empty()) {
                // The first and second moments of the optical depth's position in the slab.
                // Weighted by the optical depth summed over R, G, B, the same in both paths.
                const float w = shares[j] * (s.tau[0] + s.tau[1] + s.tau[2]);
                const std::size_t mb = slot(s.firstSlab + j) * kTilePixels + std::size_t(p);
                add(&mMoment[mb], w * moments[2 * j]);
                add(&mMoment2[mb], w * moments[2 * j + 1]);
                if (shift && !mShift.empty() && w > 0.0f) {
                    // Motion blur: the optical depth's mean move, to look its light up where
                    // its material is in the still field (shiftOf).
                    // With shutter layers, per layer: a piece of a path on some, on theirs,
                    // weighed as its optical depth there; the others on every layer.
                    const int first = layered ? layerFirst : 0, last = layered ? layerLast : mLayerTau.empty() ? 1 : mLayers;
                    const float weight = layered ? w * (float(mLayers) / float(last - first)) : w;
                    for (int b = first; b < last; ++b) {
                        const std::size_t sb = shiftIndex(s.firstSlab + j, b) + std::size_t(p);
                        for (int k = 0; k < 3; ++k) add(&mShift[sb + std::size_t(k) * kTilePixels], weight * shift[k]);
                        add(&mShift[sb + 3 * kTilePixels], weight);
                    }
                }
            }
            for (int c = 0; c < C; ++c) {
                if (!layered) {
                    add(&mTau[base + std::size_t(c) * kTilePixels], shares[j] * s.tau[c]);
                } else {
                    // Motion blur's shutter layers: the piece's optical depth over its part of
                    // the shutter, the layers' mean its share (foldLayers).
                    const float each = shares[j] * s.tau[c] * float(mLayers) / float(layerLast - layerFirst);
                    for (int k = layerFirst; k < layerLast; ++k) add(&mLayerTau[layerIndex(s.firstSlab + j, k, c) + std::size_t(p)], each);
                }
                if (!mEmission.empty()) add(&mEmission[base + std::size_t(c) * kTilePixels], shares[j] * s.emission[c]);
                if (!mScatter.empty()) add(&mScatter[base + std::size_t(c) * kTilePixels], shares[j] * s.scatter[c]);
                for (int k = 0; k < mPassCount; ++k)
                    add(&mPassEmission[passIndex(s.firstSlab + j, k, c) + std::size_t(p)], shares[j] * passSources[3 * k + c]);
            }
        }
    }

    /// Flush every pending slab and write the tile's pixels and passes. @a depthScale: camera
    /// depth per unit of distance along each pixel's ray (frame order).
    void finish(Frame& frame, const std::vector<float>& depthScale, TileDeep* deep)
    {
        if (mCompositeLevel > 0) {
            mLevels[std::size_t(mCompositeLevel - 1)]->flushUpTo(std::numeric_limits<std::int64_t>::max());
            leaveLevel(); // the level's colour, transmittance and passes onto the pixels
        }
        flushUpTo(std::numeric_limits<std::int64_t>::max());
        // Surfaces behind every slab of their pixel.
        for (int p = 0; p < kTilePixels; ++p) {
            if (mSurfacePending[p] && mAlive[p]) compositeSurface(p, std::numeric_limits<float>::infinity());
        }
        const PassRequest& passes = mOptions.passes;
        const int width = frame.beauty.width;
        for (int ly = 0; ly < mH; ++ly)
            for (int lx = 0; lx < mW; ++lx) {
                const int p = ly * kTileSize + lx;
                const std::size_t i = std::size_t(mY0 + ly) * std::size_t(width) + std::size_t(mX0 + lx);
                float* px = frame.beauty.pixel(mX0 + lx, mY0 + ly);
                for (int c = 0; c < 3; ++c) px[c] = mC[channel(c) * kTilePixels + p];
                px[3] = 1.0f - meanT(p);
                if (passes.depth) frame.depth[i] = mZ[p] * depthScale[i];
                if (passes.transmittance) {
                    for (int c = 0; c < 3; ++c) frame.transmittance[3 * i + c] = mT[channel(c) * kTilePixels + p];
                }
                for (const auto& [k, pass] : {std::pair{mOptions.layout.shadow, &frame.shadow}, std::pair{mOptions.layout.emission, &frame.emission}}) {
                    if (k < 0) continue;
                    for (int c = 0; c < 3; ++c) (*pass)[3 * i + c] = mPassC[(std::size_t(k) * C + channel(c)) * kTilePixels + p];
                }
            }
        if (deep) {
            // Group the samples by pixel; a stable sort keeps each pixel's depth order.
            std::stable_sort(mDeep.begin(), mDeep.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
            deep->samples.reserve(mDeep.size());
            for (const auto& [p, sample] : mDeep) {
                ++deep->counts[p];
                deep->samples.push_back(sample);
            }
        }
    }

private:
    /// @a f(plane, floats) for each ring array in use, with the floats one slot holds.
    template <typename F>
    void forEachSlotPlane(F&& f)
    {
        for (const auto& [plane, floats] : slotPlanes()) {
            if (!plane->empty() && floats > 0) f(*plane, floats);
        }
    }

    /// Every ring array and the floats one slot holds, in use or not, in the same order for
    /// every tile and level of a frame.
    std::array<std::pair<std::vector<float>*, std::size_t>, 8> slotPlanes()
    {
        return {{{&mTau, C * kTilePixels}, {&mEmission, C * kTilePixels}, {&mScatter, C * kTilePixels},
            {&mPassEmission, std::size_t(mPassCount) * C * kTilePixels}, {&mMoment, kTilePixels}, {&mMoment2, kTilePixels},
            {&mShift, shiftFloats()}, {&mLayerTau, std::size_t(mLayers) * C * kTilePixels}}};
    }

    /// An image level's accumulator (levelFor): level @a level's samples of @a fine's tile, one
    /// outside it on every side (levelSplat), with no ring yet.
    struct LevelTag
    {
    };
    /// Its samples' centres lie at the frame's pixel coordinates fine.x0 + (i - 1/2) h (sampleX),
    /// where it composites when the tile is composited at the level (mCompositeLevel).
    TileCompositor(const TileCompositor& fine, LevelTag, int level)
        : mX0(0), mY0(0), mW(kTileSize / (1 << level) + 2), mH(mW), mOriginX(double(fine.mX0) - double(1 << level)),
          mOriginY(double(fine.mY0) - double(1 << level)), mSpacing(double(1 << level)), mCutoff(fine.mCutoff), mExp(fine.mExp),
          mTable(fine.mTable), mOptions(fine.mOptions), mPassCount(fine.mPassCount), mLayers(fine.mLayers),
          mPassC(std::size_t(mPassCount) * C * kTilePixels, 0.0f)
    {
        clearSamples();
    }

    /// Nothing composited yet at the samples (mW x mH): transmittance 1, no colour, no Z, no
    /// surface, every sample live.
    void clearSamples()
    {
        std::fill(std::begin(mT), std::end(mT), 1.0f);
        std::fill(std::begin(mC), std::end(mC), 0.0f);
        std::fill(std::begin(mZ), std::end(mZ), std::numeric_limits<float>::infinity());
        std::fill(std::begin(mSurfacePending), std::end(mSurfacePending), 0);
        std::fill(std::begin(mDeepBack), std::end(mDeepBack), -std::numeric_limits<float>::infinity());
        receiveEverywhere();
    }

    /// Every sample live, every row whole: a level's state before it composites, and while it
    /// only accumulates (each sample feeds pixels, whichever have stopped).
    void receiveEverywhere()
    {
        std::fill(std::begin(mAlive), std::end(mAlive), 0);
        for (int y = 0; y < kTileSize; ++y) {
            mRowFirst[y] = y < mH ? 0 : kTileSize;
            mRowLast[y] = y < mH ? mW - 1 : -1;
            for (int x = 0; x < mW && y < mH; ++x) mAlive[y * kTileSize + x] = 1;
        }
        mAliveCount = mW * mH;
    }

    /// The frame's pixel coordinates of sample column @a x's centre (a pixel's: x0 + x + 1/2).
    double sampleX(int x) const { return mOriginX + mSpacing * (double(x) + 0.5); }
    /// The same for sample row @a y.
    double sampleY(int y) const { return mOriginY + mSpacing * (double(y) + 0.5); }

    /// Add @a s's footprint (add's) at image level @a level's samples, into @a coarse (that
    /// level's accumulator, levelFor).
    void accumulateAtLevel(TileCompositor& coarse, int level, const Splat& s, const float* shares, const float* moments,
        const float* passSources, const float* shift)
    {
        const Splat at = levelSplat(s, level);
        if (at.x0 > at.x1 || at.y0 > at.y1) return;
        for (int k = 0; k < int(s.slabCount); ++k) coarse.markDirty(s.firstSlab + k, at.x0, at.y0, at.x1, at.y1);
        mLevelSamples[level] += coarse.accumulate(at, shares, moments, passSources, shift, at.x0, at.y0, at.x1, at.y1);
    }

    /// add() at the level the tile is composited at (mCompositeLevel): the level composites
    /// in front of @a s's first slab, then takes @a s's footprint at its samples.
    void addAtLevel(const Splat& s, const float* shares, const float* moments, const float* passSources, const float* shift)
    {
        TileCompositor& coarse = levelFor(mCompositeLevel);
        if (!coarse.mRaysTraced) coarse.traceRays();
        coarse.flushBefore(s.firstSlab);
        accumulateAtLevel(coarse, mCompositeLevel, s, shares, moments, passSources, shift);
    }

    /// A tile composited at a coarser level goes on at its pixels: their colour, transmittance,
    /// passes and Z reconstructed bilinearly from the level's samples (the level's taps, as
    /// foldLevels'); a pixel stops where all the samples it reads have. The level accumulates
    /// from here on, its pending slabs folded into the pixels when composited
    /// (docs/equations.md#compositing-at-a-coarser-level).
    void leaveLevel()
    {
        const int level = mCompositeLevel;
        mCompositeLevel = 0;
        TileCompositor& coarse = *mLevels[std::size_t(level - 1)];
        const LevelTaps& taps = levelTaps(level);
        mAliveCount = 0;
        for (int y = 0; y < mH; ++y)
            for (int x = 0; x < mW; ++x) {
                const int p = y * kTileSize + x;
                // The four samples pixel p reads (row-major from the top left) and their weights.
                const int i = taps.index[y] * kTileSize + taps.index[x];
                const int q[4] = {i, i + 1, i + kTileSize, i + kTileSize + 1};
                const float fx = taps.frac[x], fy = taps.frac[y];
                const float w[4] = {(1.0f - fx) * (1.0f - fy), fx * (1.0f - fy), (1.0f - fx) * fy, fx * fy};
                const auto at = [&](const float* plane) {
                    const float top = plane[q[0]] + fx * (plane[q[1]] - plane[q[0]]);
                    const float bottom = plane[q[2]] + fx * (plane[q[3]] - plane[q[2]]);
                    return top + fy * (bottom - top);
                };
                for (int c = 0; c < C; ++c) {
                    mT[c * kTilePixels + p] = at(coarse.mT + c * kTilePixels);
                    mC[c * kTilePixels + p] = at(coarse.mC + c * kTilePixels);
                }
                for (int k = 0; k < mPassCount * C; ++k) mPassC[std::size_t(k) * kTilePixels + std::size_t(p)] = at(&coarse.mPassC[std::size_t(k) * kTilePixels]);
                // Z: where the pixel's alpha has crossed 0.5, the mean of the samples' crossings.
                float z = 0.0f, zw = 0.0f;
                bool alive = false;
                for (int j = 0; j < 4; ++j) {
                    if (!(w[j] > 0.0f)) continue;
                    alive = alive || coarse.mAlive[q[j]];
                    if (std::isfinite(coarse.mZ[q[j]])) z += w[j] * coarse.mZ[q[j]], zw += w[j];
                }
                mZ[p] = zw > 0.0f && meanT(p) <= 0.5f ? z / zw : std::numeric_limits<float>::infinity();
                mAlive[p] = alive;
                mAliveCount += alive;
            }
        for (int y = 0; y < mH; ++y) {
            mRowFirst[y] = 0;
            mRowLast[y] = mW - 1;
            trimRow(y);
        }
        // The level's pending slabs: folded into the pixels' when composited (flush), into
        // boxes foldLevels grows.
        for (const std::int64_t slab : coarse.mPending) markDirty(slab, mW, mH, -1, -1);
        coarse.receiveEverywhere();
    }

    /// The image level splat @a s is accumulated at (CompositeOptions::imageLod): the coarsest
    /// whose samples, 2^level pixels apart, its narrowest standard deviation spans at least
    /// imageLod times (0: every pixel).
    int levelOf(const Splat& s) const
    {
        if (!(mOptions.imageLod > 0.0f)) return 0;
        // Q = Sigma^-1 (Eq. 33): the narrowest standard deviation is 1 / sqrt(Q's largest eigenvalue).
        const double mean = 0.5 * (double(s.qa) + double(s.qc)), half = 0.5 * (double(s.qa) - double(s.qc));
        const double sigma = 1.0 / std::sqrt(mean + std::sqrt(half * half + double(s.qb) * double(s.qb)));
        int level = 0;
        while (level + 1 < kImageLevels && sigma >= double(mOptions.imageLod) * double(1 << (level + 1))) ++level;
        return level;
    }

    /// @a s in image level @a level's sample coordinates: the level's sample (i, j) lies at the
    /// tile's pixel coordinates ((i - 1/2) h, (j - 1/2) h), h = 2^level, as a pixel's centre at
    /// (i + 1/2, j + 1/2); its box: the samples whose centres lie in its cut-off box.
    Splat levelSplat(const Splat& s, int level) const
    {
        const double h = double(1 << level);
        Splat at = s;
        at.cx = float((double(s.cx) - mX0) / h + 1.0);
        at.cy = float((double(s.cy) - mY0) / h + 1.0);
        at.qa = float(double(s.qa) * h * h);
        at.qb = float(double(s.qb) * h * h);
        at.qc = float(double(s.qc) * h * h);
        const int last = kTileSize / (1 << level) + 1;
        const double det = double(at.qa) * double(at.qc) - double(at.qb) * double(at.qb);
        // Half-widths of the ellipse d^T Q d = cutoff's box (huge or degenerate: the level).
        const double rx = det > 0.0 ? std::sqrt(double(s.cutoff) * double(at.qc) / det) : double(last + 1);
        const double ry = det > 0.0 ? std::sqrt(double(s.cutoff) * double(at.qa) / det) : double(last + 1);
        const auto first = [&](double c, double r) { return int(std::clamp(std::ceil(c - r - 0.5), 0.0, double(last) + 1.0)); };
        const auto final = [&](double c, double r) { return int(std::clamp(std::floor(c + r - 0.5), -1.0, double(last))); };
        at.x0 = first(at.cx, rx);
        at.x1 = final(at.cx, rx);
        at.y0 = first(at.cy, ry);
        at.y1 = final(at.cy, ry);
        return at;
    }

    /// Image level @a level's accumulator, with a ring as large as the tile's.
    TileCompositor& levelFor(int level)
    {
        std::unique_ptr<TileCompositor>& coarse = mLevels[std::size_t(level - 1)];
        if (!coarse) coarse.reset(new TileCompositor(*this, LevelTag{}, level));
        coarse->ensureRing(mRingSize, std::size_t(level - 1) < mLevelSpares.size() ? &mLevelSpares[std::size_t(level - 1)] : nullptr);
        return *coarse;
    }

    /// The bilinear taps of a tile's pixels in image level @a level: pixel x reads samples
    /// index[x] and index[x] + 1 with weights 1 - frac[x] and frac[x] (the pixel's centre,
    /// (x + 1/2) / h + 1 in sample coordinates, between the samples' centres); weight[i][x]:
    /// sample i's weight at pixel x (0 but at those two), so that a row's pixels are a sum of
    /// whole-row multiply-adds, one a sample (vectorised). Levels 1 and up.
    struct LevelTaps
    {
        int index[kTileSize];
        float frac[kTileSize];
        alignas(64) float weight[kTileSize][kTileSize];
    };
    static const LevelTaps& levelTaps(int level)
    {
        static const std::array<LevelTaps, kImageLevels> taps = [] {
            std::array<LevelTaps, kImageLevels> t{};
            for (int k = 1; k < kImageLevels; ++k) // level 0 is the pixels: no taps
                for (int x = 0; x < kTileSize; ++x) {
                    LevelTaps& l = t[std::size_t(k)];
                    const double u = (double(x) + 0.5) / double(1 << k) + 0.5;
                    l.index[x] = int(std::floor(u));
                    l.frac[x] = float(u - std::floor(u));
                    l.weight[l.index[x]][x] = 1.0f - l.frac[x];
                    l.weight[l.index[x] + 1][x] = l.frac[x];
                }
            return t;
        }();
        return taps[std::size_t(level)];
    }

    /// Image-space level of detail: what the coarser levels hold of @a slab, reconstructed
    /// bilinearly at the tile's pixels and added to its planes, the levels' cleared. Every
    /// plane is a sum of footprints x constants, so this is each footprint reconstructed from
    /// its samples (docs/equations.md#image-space-level-of-detail). @a d (the slab's dirty
    /// box, on) grows to the pixels that read a sample it holds.
    void foldLevels(std::int64_t slab, Dirty& d)
    {
        for (int level = 1; level < kImageLevels; ++level) {
            TileCompositor* coarse = mLevels[std::size_t(level - 1)].get();
            if (!coarse || coarse->mRingSize == 0) continue;
            Dirty& from = coarse->mDirty[coarse->slot(slab)];
            if (!from.on || from.slab != slab) continue;
            const LevelTaps& taps = levelTaps(level);
            const auto reads = [&](int x, int a, int b) { return taps.index[x] + 1 >= a && taps.index[x] <= b; };
            int x0 = mW, x1 = -1, y0 = mH, y1 = -1;
            for (int x = 0; x < mW; ++x) {
                if (reads(x, from.x0, from.x1)) x0 = std::min(x0, x), x1 = std::max(x1, x);
            }
            for (int y = 0; y < mH; ++y) {
                if (reads(y, from.y0, from.y1)) y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
            const auto fine = slotPlanes();
            const auto planes = coarse->slotPlanes();
            for (std::size_t plane = 0; plane < planes.size(); ++plane) {
                const std::size_t floats = planes[plane].second;
                if (planes[plane].first->empty() || floats == 0) continue;
                for (std::size_t q = 0; q < floats; q += kTilePixels) {
                    float* source = planes[plane].first->data() + coarse->slot(slab) * floats + q;
                    float* target = fine[plane].first->data() + slot(slab) * floats + q;
                    // Along the dirty rows of samples (each a sum of whole-row multiply-adds,
                    // one a dirty sample), then down to each pixel row between two of them.
                    alignas(64) float rows[kTileSize + 1][kTileSize];
                    for (int i = std::max(from.y0 - 1, 0); i <= from.y1 + 1; ++i) std::fill_n(rows[i], kTileSize, 0.0f);
                    for (int i = from.y0; i <= from.y1; ++i) {
                        const float* samples = source + i * kTileSize;
                        for (int j = from.x0; j <= from.x1; ++j) {
                            const float v = samples[j];
                            for (int x = 0; x < kTileSize; ++x) rows[i][x] += v * taps.weight[j][x];
                        }
                    }
                    for (int y = y0; y <= y1; ++y) {
                        const float* a = rows[taps.index[y]];
                        const float* b = rows[taps.index[y] + 1];
                        const float fy = taps.frac[y];
                        for (int x = x0; x <= x1; ++x) target[y * kTileSize + x] += a[x] + fy * (b[x] - a[x]);
                    }
                    for (int y = from.y0; y <= from.y1; ++y) std::fill_n(source + y * kTileSize + from.x0, from.x1 - from.x0 + 1, 0.0f);
                }
            }
            if (x0 <= x1 && y0 <= y1) {
                d.x0 = std::min(d.x0, x0);
                d.y0 = std::min(d.y0, y0);
                d.x1 = std::max(d.x1, x1);
                d.y1 = std::max(d.y1, y1);
            }
            from.on = false;
            const auto pending = std::find(coarse->mPending.begin(), coarse->mPending.end(), slab);
            if (pending != coarse->mPending.end()) coarse->mPending.erase(pending);
        }
    }

    /// The image levels' rings let go (their slabs folded: park), into @a spare's levels if
    /// given, else to the allocator; with the rings lent with the tile's and not taken.
    void parkLevels(Ring* spare)
    {
        if (spare) spare->levels.resize(kImageLevels - 1);
        for (std::size_t k = 0; k + 1 < kImageLevels; ++k) {
            Ring* to = spare ? &spare->levels[k] : nullptr;
            if (mLevels[k] && mLevels[k]->mRingSize > 0) mLevels[k]->park(to);
            else if (to && k < mLevelSpares.size() && mLevelSpares[k].size > 0) *to = std::move(mLevelSpares[k]);
        }
        mLevelSpares.clear();
    }

    /// An empty ring of @a ringSize slots for @a other's options (ensureRing).
    TileCompositor(const TileCompositor& other, int ringSize)
        : mX0(other.mX0), mY0(other.mY0), mW(other.mW), mH(other.mH), mOriginX(other.mOriginX), mOriginY(other.mOriginY),
          mSpacing(other.mSpacing), mMask(ringSize - 1), mCutoff(other.mCutoff),
          mExp(other.mExp), mTable(other.mTable), mOptions(other.mOptions), mPassCount(other.mPassCount), mLayers(other.mLayers),
          mTau(std::size_t(ringSize) * C * kTilePixels, 0.0f),
          mEmission(mOptions.emissive ? std::size_t(ringSize) * C * kTilePixels : 0, 0.0f),
          mPassEmission(std::size_t(ringSize) * std::size_t(mPassCount) * C * kTilePixels, 0.0f),
          mScatter(mOptions.tinted ? std::size_t(ringSize) * C * kTilePixels : 0, 0.0f),
          mMoment(mOptions.lit() ? std::size_t(ringSize) * kTilePixels : 0, 0.0f),
          mMoment2(mOptions.lit() ? std::size_t(ringSize) * kTilePixels : 0, 0.0f),
          mShift(mOptions.lit() && mOptions.shifted ? std::size_t(ringSize) * shiftFloats() : 0, 0.0f),
          mLayerTau(mLayers > 1 ? std::size_t(ringSize) * std::size_t(mLayers) * C * kTilePixels : 0, 0.0f),
          mDirty(std::size_t(ringSize))
    {
    }

    std::size_t slot(std::int64_t slab) const { return std::size_t(slab & mMask); }
    /// Channel carried for colour channel c (all three share channel 0 when C == 1).
    static int channel(int c) { return C == 1 ? 0 : c; }
    /// Start of pass k, channel c of a slab in mPassEmission.
    std::size_t passIndex(std::int64_t slab, int k, int c) const
    {
        return ((slot(slab) * std::size_t(mPassCount) + std::size_t(k)) * C + std::size_t(c)) * kTilePixels;
    }
    /// Start of shutter layer k, channel c of a slab in mLayerTau.
    std::size_t layerIndex(std::int64_t slab, int k, int c) const
    {
        return ((slot(slab) * std::size_t(mLayers) + std::size_t(k)) * C + std::size_t(c)) * kTilePixels;
    }
    /// Start of shutter layer k, channel c in mLayerT.
    static std::size_t layerT(int k, int c) { return (std::size_t(k) * C + std::size_t(c)) * kTilePixels; }
    /// Floats of mShift per slot: a block of kShiftPlanes planes per shutter layer.
    std::size_t shiftFloats() const { return std::size_t(mLayers) * kShiftPlanes * kTilePixels; }
    /// Start of @a slab's shift block for shutter layer @a block in mShift.
    std::size_t shiftIndex(std::int64_t slab, int block) const
    {
        return slot(slab) * shiftFloats() + std::size_t(block) * kShiftPlanes * kTilePixels;
    }

    /// Motion blur's shutter layers, at the tile's first splat that covers only some of them:
    /// every layer starts from the transmittance so far (until then they were all equal; a
    /// tile without such a splat composites as without layers, bit for bit).
    void splitLayers()
    {
        mLayerT.resize(std::size_t(mLayers) * C * kTilePixels);
        for (int k = 0; k < mLayers; ++k) std::copy_n(mT, C * kTilePixels, mLayerT.begin() + std::ptrdiff_t(layerT(k, 0)));
    }

    /// Motion blur's shutter layers, before @a slab is lit and composited in its dirty box
    /// @a d: the splats that covered every layer were summed in mTau, the others in their
    /// layers' planes; each layer's plane becomes that layer's optical depth (the sum plus its
    /// own), and mTau the layers' mean, which lights the slab (docs/equations.md#shutter-layers).
    void foldLayers(std::int64_t slab, const Dirty& d)
    {
        const float share = 1.0f / float(mLayers);
        for (int y = d.y0; y <= d.y1; ++y)
            for (int c = 0; c < C; ++c) {
                float* all = &mTau[slot(slab) * C * kTilePixels + std::size_t(c) * kTilePixels + std::size_t(y * kTileSize)];
                float sum[kTileSize] = {};
                for (int k = 0; k < mLayers; ++k) {
                    float* own = &mLayerTau[layerIndex(slab, k, c) + std::size_t(y * kTileSize)];
                    for (int x = d.x0; x <= d.x1; ++x) {
                        sum[x] += own[x];
                        own[x] += all[x];
                    }
                }
                for (int x = d.x0; x <= d.x1; ++x) all[x] += share * sum[x];
            }
    }

    /// The layers' mean transmittance behind @a slab at pixel p, channel c (as compositeLayers
    /// leaves it).
    float layersAfter(std::int64_t slab, int p, int c) const
    {
        float left = 0.0f;
        for (int k = 0; k < mLayers; ++k) {
            left += mLayerT[layerT(k, c) + std::size_t(p)] * (1.0f - slabAbsorbed(mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]));
        }
        return left / float(mLayers);
    }

    /// compositeSlab with motion blur's shutter layers, for channel c of pixel p: the slab's
    /// colour (its source per unit of the layers' mean absorption @a absorbed) seen through each
    /// layer's transmittance by that layer's absorption, each layer's transmittance updated with
    /// its own optical depth, mT their mean (docs/equations.md#shutter-layers).
    void compositeLayers(std::int64_t slab, int p, int c, float tau, float absorbed, float emission, float scattered)
    {
        float& colour = mC[c * kTilePixels + p];
        float& t = mT[c * kTilePixels + p];
        if (!(tau > 0.0f)) {
            if (emission > 0.0f) colour += t * emission;
            return;
        }
        float seen = 0.0f, left = 0.0f;
        for (int k = 0; k < mLayers; ++k) {
            float& tk = mLayerT[layerT(k, c) + std::size_t(p)];
            const float a = slabAbsorbed(mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]);
            seen += tk * a;
            tk *= 1.0f - a;
            left += tk;
        }
        colour += (slabEmitted(tau, absorbed, emission) + scattered) * (absorbed > 0.0f ? seen / (float(mLayers) * absorbed) : t);
        t = left / float(mLayers);
    }

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

    /// Mean transmittance over R, G, B of pixel p, with the same rounding whatever C is (so
    /// alpha is bit-identical between the grey and the three-channel paths).
    float meanT(int p) const
    {
        return (mT[p] + mT[channel(1) * kTilePixels + p] + mT[channel(2) * kTilePixels + p]) / 3.0f;
    }

    /// The passes' share of a slab at pixel p: Z crossing, deep sample, extra sources.
    /// @a emission: the slab's pre-shaded emission per channel; @a lit: the scattering weight x
    /// the light integrated across the slab per channel, summed over the lights (the shadow
    /// pass's source); @a lighted: the same with each light's colour (lightSlab).
    void flushPasses(std::int64_t slab, int p, float meanBefore, const float* emission, const float* lit, const float* lighted)
    {
        const std::size_t base = slot(slab) * C * kTilePixels + std::size_t(p);
        if (mOptions.passes.depth && meanBefore > 0.5f && std::isinf(mZ[p])) {
            const double u = halfAlphaFraction(meanBefore, meanT(p));
            if (u <= 1.0) mZ[p] = float(mOptions.slabs.start(slab) + u * mOptions.slabs.thickness);
        }
        for (int k = 0; k < mPassCount; ++k)
            for (int c = 0; c < C; ++c) {
                // The beauty's transmittance before this slab, recovered per channel.
                float t = mTBefore[c];
                const float source = mPassEmission[passIndex(slab, k, c) + std::size_t(p)];
                const float tau = mTau[base + c * kTilePixels];
                compositeSlab(tau, slabAbsorbed(tau), source, k == mOptions.layout.shadow ? lit[c] : 0.0f,
                    mPassC[(std::size_t(k) * C + c) * kTilePixels + p], t);
            }
        if (mOptions.passes.deep) {
            // The slab on its own: colour and transmittance as if nothing were in front.
            float colour[C], t[C];
            bool empty = true;
            for (int c = 0; c < C; ++c) {
                colour[c] = 0.0f;
                t[c] = 1.0f;
                const float tau = mTau[base + c * kTilePixels];
                compositeSlab(tau, slabAbsorbed(tau), emission[c], lighted[c], colour[c], t[c]);
                empty = empty && !(mTau[base + c * kTilePixels] > 0.0f) && !(emission[c] > 0.0f);
            }
            if (!empty) {
                DeepSample d;
                d.z = float(mOptions.slabs.start(slab));
                d.zBack = float(mOptions.slabs.start(slab + 1));
                d.r = colour[0];
                d.g = colour[channel(1)];
                d.b = colour[channel(2)];
                d.a = 1.0f - (t[0] + t[channel(1)] + t[channel(2)]) / 3.0f;
                mDeep.emplace_back(std::uint16_t(p), d);
                mDeepBack[p] = d.zBack;
            }
        }
    }

    std::size_t frameIndex(int p) const
    {
        return std::size_t(mY0 + p / kTileSize) * std::size_t(mOptions.surface->width) + std::size_t(mX0 + p % kTileSize);
    }

    /// Composite pixel p's surface over what lies behind it: C += T c, T *= 1 - a (c the
    /// layer's premultiplied colour, a its coverage), and its share of the passes: Z where the
    /// alpha crosses 0.5, the shadow pass (the light's transmittance at the surface), a deep
    /// point sample at the surface's depth, kept between the pixel's last deep sample and
    /// @a before (the front of the slab composited next), so the samples stay in order.
    void compositeSurface(int p, float before)
    {
        mSurfacePending[p] = 0;
        const std::size_t i = frameIndex(p);
        const float* rgba = &mOptions.surface->rgba[4 * i];
        const float meanBefore = meanT(p), z = mOptions.surfaceAt[i];
        float tBefore[C];
        float t2 = 0.0f;
        for (int c = 0; c < C; ++c) {
            float& t = mT[c * kTilePixels + p];
            tBefore[c] = t;
            mC[c * kTilePixels + p] += t * rgba[c];
            t *= 1.0f - rgba[3];
            for (int k = 0; k < (mLayerT.empty() ? 0 : mLayers); ++k) mLayerT[layerT(k, c) + std::size_t(p)] *= 1.0f - rgba[3];
            t2 += t * t;
        }
        const PassRequest& passes = mOptions.passes;
        if (passes.depth && meanBefore > 0.5f && meanT(p) <= 0.5f && std::isinf(mZ[p])) mZ[p] = z;
        if (mOptions.layout.shadow >= 0 && mOptions.surfaceShadow) {
            for (int c = 0; c < C; ++c) {
                mPassC[(std::size_t(mOptions.layout.shadow) * C + std::size_t(c)) * kTilePixels + std::size_t(p)] +=
                    tBefore[c] * mOptions.surfaceShadow->rgba[4 * i + std::size_t(c)];
            }
        }
        if (passes.deep) {
            DeepSample d;
            d.z = d.zBack = std::max(std::min(z, before), mDeepBack[p]);
            d.r = rgba[0];
            d.g = rgba[1];
            d.b = rgba[2];
            d.a = rgba[3];
            mDeep.emplace_back(std::uint16_t(p), d);
        }
        if (t2 * float(3 / C) < mCutoff) terminate(p);
    }

    /// The fraction of the slab at @a base in front of where pixel p's |T_rgb|^2 falls to the
    /// cutoff (the slab's optical depth taken as uniform across it); 1 if it does not.
    float terminationFraction(std::int64_t slab, std::size_t base, int p) const
    {
        // |T(u)|^2 = sum_c T_c^2 exp(-2 u tau_c): its logarithm falls with u and is convex (a
        // log-sum-exp of lines), so Newton's method on ln|T(u)|^2 - ln cutoff from u = 0 climbs
        // to the crossing from below without overshooting, quadratically; one exact step when
        // the channels are equal (C == 1: a line, without shutter layers).
        // With shutter layers T_c(u) is the layers' mean: its square is the sum over pairs of
        // layers k, l of T_kc T_lc / L^2 exp(-u (tau_kc + tau_lc)), a log-sum-exp of lines too;
        // with one channel, the mean's square (ln of it: 2 ln of a log-sum-exp, as convex),
        // L terms instead of L^2. Terms w exp(-u beta); as composited, a slab's optical depth
        // counts from 0 (halo kernels weigh negative).
        const int layers = mLayerT.empty() ? 1 : mLayers;
        const bool meanSquared = layers > 1 && C == 1;
        double w[C * kMaxShutterLayers * kMaxShutterLayers], beta[C * kMaxShutterLayers * kMaxShutterLayers];
        int terms = 0;
        for (int c = 0; c < C; ++c) {
            if (meanSquared) {
                for (int k = 0; k < layers; ++k) {
                    w[terms] = double(mLayerT[layerT(k, c) + std::size_t(p)]) / double(layers);
                    beta[terms++] = std::max(double(mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]), 0.0);
                }
                continue;
            }
            if (layers == 1) {
                const double t = mT[c * kTilePixels + p];
                w[terms] = t * t;
                beta[terms++] = 2.0 * std::max(double(mTau[base + std::size_t(c) * kTilePixels + std::size_t(p)]), 0.0);
                continue;
            }
            for (int k = 0; k < layers; ++k)
                for (int l = 0; l < layers; ++l) {
                    w[terms] = double(mLayerT[layerT(k, c) + std::size_t(p)]) * double(mLayerT[layerT(l, c) + std::size_t(p)]) / double(layers * layers);
                    beta[terms++] = std::max(double(mLayerTau[layerIndex(slab, k, c) + std::size_t(p)]), 0.0) +
                                    std::max(double(mLayerTau[layerIndex(slab, l, c) + std::size_t(p)]), 0.0);
                }
        }
        const auto t2At = [&](double u, double* slope) {
            double f = 0.0, df = 0.0;
            for (int i = 0; i < terms; ++i) {
                const double e = w[i] * std::exp(-u * beta[i]);
                f += e;
                df -= beta[i] * e;
            }
            if (meanSquared) { // f: the mean transmittance
                if (slope) *slope = 3.0 * 2.0 * f * df;
                return 3.0 * f * f;
            }
            // C == 1: the three equal channels, scaled after the sum as e + e + e == 3 e.
            if (slope) *slope = df * double(3 / C);
            return f * double(3 / C);
        };
        const double logCutoff = std::log(double(mCutoff));
        // (Shutter layers: their caller found the back below the cutoff, layersAfter.)
        if ((layers == 1 && !(t2At(1.0, nullptr) < double(mCutoff))) || !(t2At(0.0, nullptr) >= double(mCutoff))) return 1.0f;
        double u = 0.0;
        for (int n = 0; n < 32; ++n) {
            double slope;
            const double f = t2At(u, &slope);
            const double step = (std::log(f) - logCutoff) * f / -slope;
            // Shutter layers: to 1e-4 of the slab (their sums of exponentials take a few steps).
            if (!(step > (layers > 1 ? 1e-4 : 1e-9))) break;
            u += step;
            if (C == 1 && layers == 1) break;
        }
        return float(std::min(u, 1.0));
    }

    /// Light @a l on pixel p's ray across the layer from fraction @a u0 to @a u1 of @a slab's
    /// thickness, for the C channels carried: its transmittance at the front, and ln(front /
    /// back) (slabLightIntegral).
    void lightAt(std::size_t l, int p, std::int64_t slab, float u0, float u1, const Vec3d& shift, std::array<float, 3>& front,
        std::array<float, 3>& logRatio) const
    {
        const double z = mOptions.slabs.start(slab);
        const double z0 = z + double(u0) * mOptions.slabs.thickness, z1 = z + double(u1) * mOptions.slabs.thickness;
        float d0, d1;
        const LightRays& r = mRays[l];
        const LightMap& map = *mOptions.lights[l].map;
        const Vec3d base = Vec3d(r.base[0][p], r.base[1][p], r.base[2][p]) - map.direction(shift), dir(r.dir[0][p], r.dir[1][p], r.dir[2][p]);
        map.densityDepths(base + z0 * dir, base + z1 * dir, d0, d1);
        if (C == 1) {
            const float log0 = map.greyLogTransmittanceOfDepth(d0);
            front[0] = std::exp(log0);
            logRatio[0] = lightLogRatio(log0, map.greyLogTransmittanceOfDepth(d1));
        } else {
            const std::array<float, 3> log0 = map.logTransmittanceOfDepth(d0);
            const std::array<float, 3> log1 = map.logTransmittanceOfDepth(d1);
            for (std::size_t c = 0; c < 3; ++c) {
                front[c] = std::exp(log0[c]);
                logRatio[c] = lightLogRatio(log0[c], log1[c]);
            }
        }
    }

    void flush(std::int64_t slab)
    {
        Dirty& d = mDirty[slot(slab)];
        foldLevels(slab, d);
        if (!mLayerT.empty()) foldLayers(slab, d);
        if (!mOptions.lights.empty()) ensureLight(slab, d);
        for (int ly = d.y0; ly <= d.y1; ++ly) flushRow(slab, ly, d.x0, d.x1);
        d.on = false;
    }

    /// Light on demand (raster/light_on_demand.h): before @a slab is lit, the light-map rays
    /// that its lookups read are marched, where a map is marched on demand. Only the live
    /// pixels of its dirty box @a d holding optical depth are lit, on their layers (layerOf):
    /// a slab behind pixels that stopped marches nothing.
    void ensureLight(std::int64_t slab, const Dirty& d) const
    {
        // The whole frame's maps are marched already: no pass over the pixels for them.
        if (std::none_of(mOptions.lights.begin(), mOptions.lights.end(), [](const CompositeLight& l) { return l.map->onDemand(); })) return;
        const double z = mOptions.slabs.start(slab), thickness = mOptions.slabs.thickness;
        // Light @a light's lookups by the pixels (x0..x1, y0..y1) between fractions u0 and u1
        // of the slab, and where their moved material came from (within maxShift).
        const auto box = [&](const CompositeLight& light, int x0, int y0, int x1, int y1, float u0, float u1, Vec3d& lo, Vec3d& hi) {
            lookupBox(*mOptions.camera, *light.map, sampleX(x0), sampleY(y0), sampleX(x1), sampleY(y1), z + double(u0) * thickness, z + double(u1) * thickness, lo, hi);
            if (mShift.empty()) return;
            Vec3d pad(0.0);
            for (int k = 0; k < 3; ++k) {
                Vec3d axis(0.0);
                axis[k] = mOptions.maxShift;
                pad += glm::abs(light.map->direction(axis));
            }
            lo -= pad;
            hi += pad;
        };
        // Most slabs read rays marched already, by an earlier slab or a neighbouring tile: the
        // box of the whole dirty box and the whole slab says so without a pass over the pixels.
        const bool marched = std::all_of(mOptions.lights.begin(), mOptions.lights.end(), [&](const CompositeLight& light) {
            Vec3d lo, hi;
            box(light, d.x0, d.y0, d.x1, d.y1, 0.0f, 1.0f, lo, hi);
            return light.map->marchedIn(lo, hi);
        });
        if (marched) return;
        int x0 = kTileSize, x1 = -1, y0 = kTileSize, y1 = -1;
        float u0 = 1.0f, u1 = 0.0f;
        const std::size_t base = slot(slab) * C * kTilePixels;
        for (int y = d.y0; y <= d.y1; ++y)
            for (int x = std::max(d.x0, mRowFirst[y]); x <= std::min(d.x1, mRowLast[y]); ++x) {
                const int p = y * kTileSize + x;
                const float mass = slabMass(base, p);
                if (!mAlive[p] || !(mass > 0.0f)) continue;
                x0 = std::min(x0, x);
                x1 = std::max(x1, x);
                y0 = std::min(y0, y);
                y1 = std::max(y1, y);
                float a, b;
                layerOf(slab, p, mass, a, b);
                u0 = std::min(u0, a);
                u1 = std::max(u1, b);
            }
        if (x0 > x1) return;
        for (const CompositeLight& light : mOptions.lights) {
            Vec3d lo, hi;
            box(light, x0, y0, x1, y1, u0, u1, lo, hi);
            light.map->ensureMarched(lo, hi);
        }
    }

    /// Motion blur's shutter layers, the light following the material: pixel p's optical
    /// depth in @a slab holds pieces of paths on some layers only (each layer is then lit
    /// where its own material came from: lightSlab).
    bool ownLayers(std::int64_t slab, int p) const
    {
        if (mLayerT.empty() || mShift.empty()) return false;
        const float weight = mShift[shiftIndex(slab, 0) + 3 * kTilePixels + std::size_t(p)];
        for (int k = 1; k < mLayers; ++k) {
            // The splats on every layer add the same to each, in the same order.
            if (mShift[shiftIndex(slab, k) + 3 * kTilePixels + std::size_t(p)] != weight) return true;
        }
        return false;
    }

    /// Motion blur: the mean move of pixel p's optical depth in @a slab from where its material
    /// is in the still field (world; 0 without motion): the light is looked up there, as the
    /// reference carries each point's light along its path (docs/equations.md#motion-blur).
    /// With shutter layers, of shutter layer @a layer's optical depth (the splats on every
    /// layer and the pieces on that one): where no piece is on some layers only (ownLayers),
    /// every layer's is the whole's.
    /// Weighed by the positive optical depths alone: halo kernels weigh negative, and a mass
    /// that nearly cancelled would throw the mean anywhere; this one stays among the moves
    /// (light on demand marches no further than the largest).
    Vec3d shiftOf(std::int64_t slab, int p, int layer = 0) const
    {
        if (mShift.empty()) return Vec3d(0.0);
        const std::size_t m = shiftIndex(slab, layer) + std::size_t(p);
        const float weight = mShift[m + 3 * kTilePixels];
        if (!(weight > 0.0f)) return Vec3d(0.0);
        return Vec3d(mShift[m] / weight, mShift[m + kTilePixels] / weight, mShift[m + 2 * kTilePixels] / weight);
    }

    /// Where pixel p's @a mass (> 0) of @a slab lies, as a uniform layer with the mean and
    /// variance of its position: from fraction @a u0 to @a u1 of the slab's thickness.
    void layerOf(std::int64_t slab, int p, float mass, float& u0, float& u1) const
    {
        const std::size_t m = slot(slab) * kTilePixels + std::size_t(p);
        const float mean = std::clamp(mMoment[m] / mass, 0.0f, 1.0f);
        const float half = std::sqrt(3.0f * std::max(mMoment2[m] / mass - mean * mean, 0.0f));
        u0 = std::max(mean - half, 0.0f);
        u1 = std::min(mean + half, 1.0f);
    }

    /// Composite @a slab at pixels (x0..x1, y) of the tile (flushPixel's result at each) and
    /// clear their accumulators (clearPixel). Defined by each backend.
    void flushRow(std::int64_t slab, int y, int x0, int x1);

    /// Pixel p's surface, if it lies in front of @a slab's middle, then the slab itself.
    void flushPixel(std::int64_t slab, int p)
    {
        const std::size_t base = slot(slab) * C * kTilePixels;
        const bool passes = mPassCount > 0 || mOptions.passes.depth || mOptions.passes.deep;
        // A surface in front of the slab's middle comes first.
        if (surfaceInFront(slab, p)) compositeSurface(p, float(mOptions.slabs.start(slab)));
        if (!mAlive[p]) return;
        float meanBefore = 0.0f;
        if (passes) {
            for (int c = 0; c < C; ++c) mTBefore[c] = mT[c * kTilePixels + p];
            meanBefore = meanT(p);
        }
        // emission: the splats' pre-shaded sources; lit: the scattering weight x the
        // light integrated across the slab (slabLightIntegral), per unit light colour, summed
        // over the lights; lighted: the same, each light with its colour.
        float emission[C], lit[C], lighted[C];
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + c * kTilePixels + std::size_t(p);
            // Halo kernels (--prefilter) weigh negative: a slab's sums stay >= 0.
            emission[c] = mEmission.empty() ? 0.0f : std::max(mEmission[i], 0.0f);
            lit[c] = lighted[c] = 0.0f;
        }
        const float mass = slabMass(base, p);
        float absorbed[C]; // 1 - exp(-tau), once per channel for light, termination, composite
        for (int c = 0; c < C; ++c) absorbed[c] = slabAbsorbed(mTau[base + c * kTilePixels + std::size_t(p)]);
        if (mOptions.lit() && mass > 0.0f) lightSlab(slab, p, mass, lit, lighted);
        // vdb_render's ray termination: |T|^2 < cutoff (early termination, Sec. 5).
        // A ray stops where it crosses the threshold, so only the slab's part in
        // front of the crossing is composited: every stopped pixel keeps vdb_render's
        // residual (about sqrt(cutoff / 3)), whatever the slab thickness.
        // (No optical depth: the ray goes on, and terminationFraction would say so.)
        // The exact crossing (in double) only where the slab's back is below the cutoff.
        float t2After = 0.0f;
        for (int c = 0; c < C; ++c) {
            const float t = mLayerT.empty() ? mT[c * kTilePixels + p] * (1.0f - absorbed[c]) : layersAfter(slab, p, c);
            t2After += t * t;
        }
        const float u = mass > 0.0f && t2After * float(3 / C) < mCutoff ? terminationFraction(slab, base, p) : 1.0f;
        if (u < 1.0f) {
            keepFront(slab, p, u);
            for (int c = 0; c < C; ++c) {
                const std::size_t i = base + c * kTilePixels + std::size_t(p);
                const float before = absorbed[c];
                absorbed[c] = slabAbsorbed(mTau[i]);
                emission[c] *= u;
                // The light kept its value across the slab, (1 - exp(-tau)) / tau of it
                // integrated (slabLightIntegral = slabLightTransmittance x that): the
                // front part keeps the same light with its own (1 - exp(-u tau)) / (u tau).
                const float kept = before > 0.0f ? absorbed[c] / before : 0.0f;
                lit[c] *= kept;
                lighted[c] *= kept;
            }
        }
        float t2 = 0.0f; // |T|^2 over R, G, B
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + c * kTilePixels + std::size_t(p);
            float& t = mT[c * kTilePixels + p];
            if (mLayerT.empty()) compositeSlab(mTau[i], absorbed[c], emission[c], lighted[c], mC[c * kTilePixels + p], t);
            else compositeLayers(slab, p, c, mTau[i], absorbed[c], emission[c], lighted[c]);
            t2 += t * t;
        }
        if (passes) flushPasses(slab, p, meanBefore, emission, lit, lighted);
        ++mComposites;
        if (u < 1.0f || t2 * float(3 / C) < mCutoff) terminate(p);
    }

    /// Pixel p's ray stops at fraction @a u of @a slab: its optical depth, the passes' sources
    /// and the shutter layers' optical depths keep the part in front of the crossing.
    void keepFront(std::int64_t slab, int p, float u)
    {
        for (int c = 0; c < C; ++c) {
            mTau[slot(slab) * C * kTilePixels + std::size_t(c) * kTilePixels + std::size_t(p)] *= u;
            for (int k = 0; k < mPassCount; ++k) mPassEmission[passIndex(slab, k, c) + std::size_t(p)] *= u;
            for (int k = 0; k < (mLayerTau.empty() ? 0 : mLayers); ++k) mLayerTau[layerIndex(slab, k, c) + std::size_t(p)] *= u;
        }
    }

    /// Pixel p's surface is still to be composited and lies in front of @a slab's middle.
    bool surfaceInFront(std::int64_t slab, int p) const
    {
        return mSurfacePending[p] && mAlive[p] &&
               mOptions.surfaceAt[frameIndex(p)] < float(mOptions.slabs.start(slab) + 0.5 * mOptions.slabs.thickness);
    }

    /// The slab's optical depth at pixel p summed over R, G, B (as in add()).
    float slabMass(std::size_t base, int p) const
    {
        float mass = 0.0f;
        for (int c = 0; c < 3; ++c) mass += mTau[base + std::size_t(channel(c)) * kTilePixels + std::size_t(p)];
        return mass;
    }

    /// Shading per slab sample (docs/numerics.md#shading-per-slab-sample): the slab's @a mass
    /// (> 0) at pixel p, as a uniform layer with the mean and variance of its position, lit by
    /// each light's transmittance at the layer's front and back and integrated with the slab's
    /// own attenuation: @a lit, the scattering weight x slabLightIntegral per channel summed
    /// over the lights; @a lighted, each term times its light's scale (CompositeLight).
    void lightSlab(std::int64_t slab, int p, float mass, float* lit, float* lighted) const
    {
        const std::size_t base = slot(slab) * C * kTilePixels;
        float u0, u1;
        layerOf(slab, p, mass, u0, u1);
        float tau[C], weight[C];
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + c * kTilePixels + std::size_t(p);
            tau[c] = mTau[i];
            weight[c] = std::max(mScatter.empty() ? mTau[i] : mScatter[i], 0.0f);
        }
        if (!ownLayers(slab, p)) {
            lightLayer(slab, p, u0, u1, shiftOf(slab, p), tau, weight, lit, lighted); // every layer's move the same
            return;
        }
        // Motion blur's shutter layers with the light following the material: each layer lit
        // where its own material came from, by its own optical depth, and seen through its
        // own transmittance; the sum returned as the source per unit of the layers' mean
        // absorption that compositeLayers spreads over them (docs/equations.md#shutter-layers).
        float seen[C] = {}, litSeen[C] = {}, lightedSeen[C] = {};
        for (int k = 0; k < mLayers; ++k) {
            float tauK[C], weightK[C], litK[C] = {}, lightedK[C] = {};
            for (int c = 0; c < C; ++c) {
                tauK[c] = mLayerTau[layerIndex(slab, k, c) + std::size_t(p)];
                // The layer's scattering weight: the slab's, in proportion to its optical depth.
                weightK[c] = mScatter.empty() ? std::max(tauK[c], 0.0f) : tau[c] > 0.0f ? weight[c] * std::max(tauK[c], 0.0f) / tau[c] : weight[c];
            }
            lightLayer(slab, p, u0, u1, shiftOf(slab, p, k), tauK, weightK, litK, lightedK);
            for (int c = 0; c < C; ++c) {
                const float t = mLayerT[layerT(k, c) + std::size_t(p)];
                seen[c] += t * slabAbsorbed(tauK[c]);
                litSeen[c] += t * litK[c];
                lightedSeen[c] += t * lightedK[c];
            }
        }
        for (int c = 0; c < C; ++c) {
            const float absorbed = slabAbsorbed(tau[c]);
            // (The ratio first: the transmittances may be denormal. Nothing seen through any
            // layer: their mean, which composites nothing.)
            const bool through = seen[c] > kSeenFloor && absorbed > 0.0f;
            lit[c] += through ? litSeen[c] / seen[c] * absorbed : litSeen[c] / float(mLayers);
            lighted[c] += through ? lightedSeen[c] / seen[c] * absorbed : lightedSeen[c] / float(mLayers);
        }
    }

    /// lightSlab's sums for a slab sample across the layer from fraction @a u0 to @a u1 of
    /// @a slab's thickness, of optical depth @a tau and scattering weight @a weight per channel,
    /// its material moved by @a shift (world) from where it is lit (shiftOf).
    void lightLayer(std::int64_t slab, int p, float u0, float u1, const Vec3d& shift, const float* tau, const float* weight,
        float* lit, float* lighted) const
    {
        if (shaped()) {
            shapedLightLayer(slab, p, u0, u1, shift, tau, weight, lit, lighted);
            return;
        }
        for (std::size_t l = 0; l < mOptions.lights.size(); ++l) {
            std::array<float, 3> front, logRatio;
            lightAt(l, p, slab, u0, u1, shift, front, logRatio);
            for (int c = 0; c < C; ++c) {
                const float term = weight[c] * slabLightIntegral(tau[c], front[std::size_t(c)], logRatio[std::size_t(c)]);
                lit[c] += term;
                lighted[c] += mOptions.lights[l].scale[c] * term;
            }
        }
        if (!mOptions.pointLights) return;
        const PointLights& points = *mOptions.pointLights;
        for (std::size_t l = 0; l < points.maps().size(); ++l) {
            std::array<float, 3> front, logRatio;
            float falloff;
            pointLightAt(l, p, slab, u0, u1, shift, front, logRatio, falloff);
            for (int c = 0; c < C; ++c) {
                const float term = weight[c] * slabLightIntegral(tau[c], front[std::size_t(c)], logRatio[std::size_t(c)]);
                lit[c] += term;
                lighted[c] += float(points.scale(l)[std::size_t(c)]) * falloff * term;
            }
        }
    }

    /// The light is shaped (ScatteringOctaves::shaped): an anisotropic phase or several octaves.
    bool shaped() const { return mOptions.model && mOptions.model->octaves().shaped(); }

    /// lightLayer with the phase function and the octaves (scattering_octaves.h): octave i
    /// lights the layer with the light's transmittance to the power b^i (front^(b^i), its
    /// log ratio times b^i) and weighs it by a^i x its phase at the sample (mPhase for the
    /// directional lights, pointOctaveWeights for the point lights).
    /// @a lit, the shadow pass's source, stays single scattering's, unweighted.
    void shapedLightLayer(std::int64_t slab, int p, float u0, float u1, const Vec3d& shift, const float* tau, const float* weight,
        float* lit, float* lighted) const
    {
        const ScatteringOctaves& octaves = mOptions.model->octaves();
        const auto addLight = [&](const std::array<float, 3>& front, const std::array<float, 3>& logRatio, const float* weights, const float* scale) {
            for (int c = 0; c < C; ++c) {
                const float single = weight[c] * slabLightIntegral(tau[c], front[std::size_t(c)], logRatio[std::size_t(c)]);
                lit[c] += single;
                float sum = weights[0] * single;
                for (int i = 1; i < octaves.count(); ++i) {
                    const float b = float(octaves.extinction(i));
                    sum += weights[i] * weight[c] * slabLightIntegral(tau[c], octaveFront(front[std::size_t(c)], b), b * logRatio[std::size_t(c)]);
                }
                lighted[c] += scale[c] * sum;
            }
        };
        for (std::size_t l = 0; l < mOptions.lights.size(); ++l) {
            std::array<float, 3> front, logRatio;
            lightAt(l, p, slab, u0, u1, shift, front, logRatio);
            float weights[ScatteringOctaves::kMax];
            for (int i = 0; i < octaves.count(); ++i) weights[i] = mPhase[phaseIndex(l, i) + std::size_t(p)];
            addLight(front, logRatio, weights, mOptions.lights[l].scale);
        }
        if (!mOptions.pointLights) return;
        const PointLights& points = *mOptions.pointLights;
        for (std::size_t l = 0; l < points.maps().size(); ++l) {
            std::array<float, 3> front, logRatio;
            float falloff, weights[ScatteringOctaves::kMax];
            pointLightAt(l, p, slab, u0, u1, shift, front, logRatio, falloff);
            pointOctaveWeights(l, p, slab, u0, u1, shift, weights);
            float scale[3];
            for (int c = 0; c < 3; ++c) scale[c] = float(points.scale(l)[std::size_t(c)]) * falloff;
            addLight(front, logRatio, weights, scale);
        }
    }

    /// Where light @a l's octave @a i weights start in mPhase ([light][octave][pixel]).
    std::size_t phaseIndex(std::size_t l, int i) const
    {
        return (l * std::size_t(mOptions.model->octaves().count()) + std::size_t(i)) * kTilePixels;
    }

    /// An octave's light at a layer's front from the light's own @a front: front^b, floored
    /// as slabLightIntegral floors it.
    static float octaveFront(float front, float b) { return std::pow(std::max(front, kLightFloor), b); }

    /// Point light @a l's octave weights (ScatteringOctaves::weight) at the middle of pixel p's
    /// layer: the cosine between the direction from the sample towards the light and the ray.
    void pointOctaveWeights(std::size_t l, int p, std::int64_t slab, float u0, float u1, const Vec3d& shift, float* weights) const
    {
        const ScatteringOctaves& octaves = mOptions.model->octaves();
        const double z = mOptions.slabs.start(slab) + 0.5 * double(u0 + u1) * mOptions.slabs.thickness;
        const LightRays& r = mRays.back(); // world coordinates (traceRays)
        const Vec3d dir(r.dir[0][p], r.dir[1][p], r.dir[2][p]);
        const Vec3d at = Vec3d(r.base[0][p], r.base[1][p], r.base[2][p]) - shift + z * dir;
        const Vec3d towards = mOptions.pointLights->lights()[l].position - at;
        const double length = glm::length(towards), dirLength = glm::length(dir);
        const double cosTheta = length > 0.0 && dirLength > 0.0 ? glm::dot(towards, dir) / (length * dirLength) : 0.0;
        for (int i = 0; i < octaves.count(); ++i) weights[i] = float(octaves.weight(i, cosTheta));
    }

    /// Point light @a l on pixel p's ray across the layer from fraction @a u0 to @a u1 of
    /// @a slab's thickness (PointLights::acrossLayer at its world points).
    void pointLightAt(std::size_t l, int p, std::int64_t slab, float u0, float u1, const Vec3d& shift, std::array<float, 3>& front,
        std::array<float, 3>& logRatio, float& falloff) const
    {
        const double z = mOptions.slabs.start(slab);
        const double z0 = z + double(u0) * mOptions.slabs.thickness, z1 = z + double(u1) * mOptions.slabs.thickness;
        const LightRays& r = mRays.back(); // world coordinates (traceRays)
        const Vec3d base = Vec3d(r.base[0][p], r.base[1][p], r.base[2][p]) - shift, dir(r.dir[0][p], r.dir[1][p], r.dir[2][p]);
        mOptions.pointLights->acrossLayer(l, base + z0 * dir, base + z1 * dir, front, logRatio, falloff);
    }

    /// Each pixel's ray in each light-map's coordinates, and in world ones for the point lights,
    /// q(z) = base + z dir, z the slab coordinate
    /// (distance from the eye, or depth for orthographic cameras): at the tile's first splat,
    /// so tiles without any (the background) skip it.
    void traceRays()
    {
        mRaysTraced = true;
        if (!mOptions.lit()) return;
        // One ray per light in its map's coordinates, then (point lights) one in world ones.
        mRays.resize(mOptions.lights.size() + (mOptions.pointLights ? 1 : 0));
        // The phase function and the octaves, where the light is shaped (shapedLightLayer).
        const ScatteringOctaves* octaves = shaped() ? &mOptions.model->octaves() : nullptr;
        if (octaves) mPhase.resize(mOptions.lights.size() * std::size_t(octaves->count()) * kTilePixels);
        const Camera& camera = *mOptions.camera;
        for (int ly = 0; ly < mH; ++ly)
            for (int lx = 0; lx < mW; ++lx) {
                Vec3d origin, dir;
                camera.worldRay(sampleX(lx), sampleY(ly), origin, dir);
                const Vec3d base = camera.projection() == Projection::Perspective ? camera.eye() : origin - camera.near() * dir;
                if (mOptions.pointLights) {
                    for (int k = 0; k < 3; ++k) {
                        mRays.back().base[k][ly * kTileSize + lx] = base[k];
                        mRays.back().dir[k][ly * kTileSize + lx] = dir[k];
                    }
                }
                for (std::size_t l = 0; l < mOptions.lights.size(); ++l) {
                    const LightMap& map = *mOptions.lights[l].map;
                    const Vec3d q = map.coordinates(base), v = map.direction(dir);
                    for (int k = 0; k < 3; ++k) {
                        mRays[l].base[k][ly * kTileSize + lx] = q[k];
                        mRays[l].dir[k][ly * kTileSize + lx] = v[k];
                    }
                    if (octaves) {
                        // A directional light's scattering angle is the same all along the ray.
                        const double cosTheta = glm::dot(mOptions.lights[l].towards, dir) / glm::length(dir);
                        for (int i = 0; i < octaves->count(); ++i) mPhase[phaseIndex(l, i) + std::size_t(ly * kTileSize + lx)] = float(octaves->weight(i, cosTheta));
                    }
                }
            }
    }

    /// Pixel p's ray stops: |T|^2 fell below the cutoff.
    void terminate(int p)
    {
        mAlive[p] = 0;
        --mAliveCount;
        // The row's span of live pixels shrinks from whichever end p was.
        trimRow(p / kTileSize);
    }

    /// Row @a y's span of live pixels (mRowFirst, mRowLast) shrunk past stopped ones at its ends.
    void trimRow(int y)
    {
        const std::uint8_t* row = mAlive + y * kTileSize;
        while (mRowFirst[y] <= mRowLast[y] && !row[mRowFirst[y]]) ++mRowFirst[y];
        while (mRowLast[y] >= mRowFirst[y] && !row[mRowLast[y]]) --mRowLast[y];
    }

    /// Zero pixel p's accumulators of @a slab (its ring slot is reused).
    void clearPixel(std::int64_t slab, int p)
    {
        const std::size_t base = slot(slab) * C * kTilePixels;
        if (!mMoment.empty()) mMoment[slot(slab) * kTilePixels + std::size_t(p)] = mMoment2[slot(slab) * kTilePixels + std::size_t(p)] = 0.0f;
        if (!mShift.empty()) {
            for (std::size_t k = 0; k < shiftFloats(); k += kTilePixels) mShift[slot(slab) * shiftFloats() + k + std::size_t(p)] = 0.0f;
        }
        for (int c = 0; c < C; ++c) {
            const std::size_t i = base + c * kTilePixels + std::size_t(p);
            mTau[i] = 0.0f;
            if (!mEmission.empty()) mEmission[i] = 0.0f;
            if (!mScatter.empty()) mScatter[i] = 0.0f;
            for (int k = 0; k < mPassCount; ++k) mPassEmission[passIndex(slab, k, c) + std::size_t(p)] = 0.0f;
            for (int k = 0; k < (mLayerTau.empty() ? 0 : mLayers); ++k) mLayerTau[layerIndex(slab, k, c) + std::size_t(p)] = 0.0f;
        }
    }

    std::uint64_t mLevelSamples[kImageLevels] = {}, mComposites = 0; ///< counters()
    /// The coarser image levels' accumulators (imageLod), level k at k - 1; null until used.
    std::array<std::unique_ptr<TileCompositor>, kImageLevels - 1> mLevels;
    std::vector<Ring> mLevelSpares; ///< the levels' rings lent with the tile's (Ring::levels)
    int mX0, mY0, mW, mH;
    /// Where sample (0, 0)'s square starts in the frame's pixel coordinates and the samples'
    /// spacing (sampleX): the tile's corner and 1 for its pixels, a level's (LevelTag) own.
    double mOriginX, mOriginY, mSpacing = 1.0;
    /// The image level the tile is composited at (planLevel): -1 until its first splat, 0 its
    /// pixels, k > 0 level k's samples (mLevels[k - 1] composites; leaveLevel).
    int mCompositeLevel = -1;
    int mRingSize = 0;
    std::int64_t mMask = -1;
    /// park()'s copy of the pending slabs' planes (slot by slot, forEachSlotPlane's order), their
    /// dirty boxes, and the ring size they need (0: nothing spilled).
    std::vector<float> mSpill;
    std::vector<Dirty> mSpilledDirty;
    int mSpilledRing = 0;
    float mCutoff;
    ExpEvaluation mExp;
    const ExpTable* mTable;
    const CompositeOptions& mOptions;
    int mPassCount;
    int mLayers; ///< motion blur's shutter layers (CompositeOptions::layers)
    std::vector<float> mTau, mEmission; ///< [slot][channel][pixel]; mEmission empty unless emissive
    std::vector<float> mPassEmission;   ///< [slot][pass][channel][pixel]
    std::vector<float> mPassC;          ///< [pass][channel][pixel]
    /// [layer][channel][pixel] each shutter layer's transmittance, mT their mean; empty until
    /// the tile's first splat that covers only some layers (splitLayers).
    std::vector<float> mLayerT;
    std::vector<float> mScatter;        ///< [slot][channel][pixel] scattering weights (tinted only)
    /// [slot][pixel] optical depth x position in the slab (0 front, 1 back), and x its square
    /// (lit frames only): where the slab's mass lies, for shading.
    std::vector<float> mMoment, mMoment2;
    /// Motion blur: per slot, the positive optical depth x its move, x, y, z planes (world),
    /// then the positive optical depth's plane (shiftOf); with shutter layers, these four per
    /// layer (shiftIndex).
    static constexpr int kShiftPlanes = 4;
    /// Below this, a slab sample seen through the shutter layers is lit by their plain mean
    /// (lightSlab: it composites nothing a float can hold).
    static constexpr float kSeenFloor = 1e-30f;
    std::vector<float> mShift;
    /// Motion blur's shutter layers (layers > 1 only): per slot, layer and channel, the optical
    /// depth of the splats that cover only some layers, then each layer's own (foldLayers).
    std::vector<float> mLayerTau;
    std::vector<LightRays> mRays; ///< per light of CompositeOptions::lights, then (point lights) in world coordinates
    /// With shaped light (shaped()): each directional light's octave weights per pixel
    /// (ScatteringOctaves::weight at its ray's scattering angle), [light][octave][pixel].
    std::vector<float> mPhase;
    bool mRaysTraced = false; ///< traceRays ran
    float mZ[kTilePixels];              ///< Z pass along the ray, +inf until alpha reaches 0.5
    float mTBefore[C];
    std::vector<std::pair<std::uint16_t, DeepSample>> mDeep;
    std::vector<Dirty> mDirty;
    std::vector<std::int64_t> mPending; ///< slabs holding contributions, not yet composited
    float mT[C * kTilePixels];
    float mC[C * kTilePixels];
    std::uint8_t mAlive[kTilePixels];
    int mRowFirst[kTileSize], mRowLast[kTileSize]; ///< each row's first and last live pixel (first > last: none)
    std::uint8_t mSurfacePending[kTilePixels]; ///< the pixel's surface is still to be composited
    float mDeepBack[kTilePixels];              ///< the back of the pixel's last deep sample (surfaces only)
    int mAliveCount = 0;
};

int ringSizeFor(std::uint32_t maxSpan)
{
    int r = 1;
    while (r < int(maxSpan) + 1) r *= 2;
    return r;
}

/// A backend's SlabCompositor: each tile swept by a TileCompositor<C>, one task a tile.
template <int C>
class TileSweepCompositor final : public SlabCompositor
{
public:
    void composite(const SplatSet& set, const TileBins& bins, const CompositeOptions& options, const std::vector<float>& depthScale,
        Frame& frame, std::vector<TileDeep>& deep, std::vector<TileCounters>& counters, Progress* progress) const override;
    std::unique_ptr<SlabStream> stream(const CompositeOptions& options, const StreamOutput& output) const override;
};

/// A backend's SlabStream: one TileCompositor<C> per tile, kept from window to window, one task
/// a tile per window; after its window a tile spills its pending slabs and lends its ring to
/// the next tile its thread sweeps (each thread keeps up to kSpareRings spare rings).
template <int C>
class TileSweepStream final : public SlabStream
{
public:
    TileSweepStream(const CompositeOptions& options, const StreamOutput& output)
        : mOptions(options), mOutput(output), mWidth(output.frame->beauty.width), mHeight(output.frame->beauty.height),
          mTilesX((mWidth + kTileSize - 1) / kTileSize), mTiles(std::size_t(mTilesX) * std::size_t((mHeight + kTileSize - 1) / kTileSize)),
          mOpaque(mTiles.size(), 0), mSkipped(mTiles.size(), 0), mWritten(mTiles.size(), 0)
    {
    }

    void composite(const SplatSet& set, const TileBins& bins, std::int64_t windowEnd, Progress* progress) override
    {
        const std::size_t passFloats = std::size_t(set.passSourceCount) * 3;
        tbb::parallel_for(tbb::blocked_range<int>(0, int(mTiles.size()), 1), [&](const tbb::blocked_range<int>& range) {
            for (int t = range.begin(); t < range.end(); ++t) {
                const std::size_t count = std::size_t(bins.offsets[t + 1] - bins.offsets[t]);
                if (mWritten[std::size_t(t)]) { // opaque and written
                    mSkipped[std::size_t(t)] += count;
                    continue;
                }
                // No splat, and nothing pending that this window's end lets composite: as it was.
                if (count == 0 && (!mTiles[std::size_t(t)] || mTiles[std::size_t(t)]->firstPending() >= windowEnd)) continue;
                if (progress) progress->check();
                std::unique_ptr<TileCompositor<C>>& tile = mTiles[std::size_t(t)];
                if (!tile) tile = makeTile(t, 0);
                std::vector<Ring>& spares = mSpares.local();
                if (!tile->opaque()) {
                    // The smallest spare ring that is large enough.
                    const int size = ringSizeFor(std::max(bins.maxSpan[std::size_t(t)], 1u));
                    Ring* spare = nullptr;
                    for (Ring& r : spares) {
                        if (r.size >= size && (!spare || r.size < spare->size)) spare = &r;
                    }
                    tile->ensureRing(size, spare);
                }
                const std::uint32_t* order = bins.indices.data() + bins.offsets[t];
                tile->planLevel(set, order, count);
                std::size_t done = 0;
                for (; done < count && !tile->opaque(); ++done) {
                    const Splat& s = set.splats[order[done]];
                    tile->add(s, set.shares.data() + s.shareOffset, set.shareMoments.data() + 2 * s.shareOffset,
                        passFloats ? set.passSources.data() + order[done] * passFloats : nullptr,
                        set.shifts.empty() ? nullptr : set.shifts.data() + 3 * std::size_t(order[done]));
                }
                mSkipped[std::size_t(t)] += count - done;
                tile->flushUpTo(windowEnd);
                mOpaque[std::size_t(t)] = tile->opaque();
                // The tile lends its ring to the next tile this thread sweeps (its pending
                // slabs spilled), or to the allocator when the thread has kSpareRings.
                Ring* spare = nullptr;
                for (Ring& r : spares) {
                    if (r.size == 0) spare = &r;
                }
                if (!spare && spares.size() < kSpareRings) spare = &spares.emplace_back();
                tile->park(spare);
                // Opaque, or the frame's last window: written now, its memory back at once.
                if (tile->opaque() || windowEnd == std::numeric_limits<std::int64_t>::max()) write(t);
            }
        });
    }

    bool opaque(int t) const override { return mOpaque[std::size_t(t)] != 0; }

    void finish() override
    {
        tbb::parallel_for(tbb::blocked_range<int>(0, int(mTiles.size()), 1), [&](const tbb::blocked_range<int>& range) {
            for (int t = range.begin(); t < range.end(); ++t) {
                if (!mWritten[std::size_t(t)]) write(t);
            }
        });
    }

private:
    /// Write tile t's pixels, passes, deep samples and counters, and let it go.
    void write(int t)
    {
        std::unique_ptr<TileCompositor<C>>& tile = mTiles[std::size_t(t)];
        if (!tile) tile = makeTile(t, 0);
        if (tile->pending()) tile->ensureRing(1); // the spilled slabs back in a ring
        tile->finish(*mOutput.frame, *mOutput.depthScale, mOutput.deep->empty() ? nullptr : &(*mOutput.deep)[std::size_t(t)]);
        (*mOutput.counters)[std::size_t(t)] = tile->counters(mSkipped[std::size_t(t)]);
        tile.reset();
        mWritten[std::size_t(t)] = 1;
    }

    std::unique_ptr<TileCompositor<C>> makeTile(int t, int ringSize) const
    {
        const int x0 = (t % mTilesX) * kTileSize, y0 = (t / mTilesX) * kTileSize;
        return std::make_unique<TileCompositor<C>>(x0, y0, std::min(kTileSize, mWidth - x0), std::min(kTileSize, mHeight - y0), ringSize, mOptions);
    }

    using Ring = typename TileCompositor<C>::Ring;
    static constexpr std::size_t kSpareRings = 4;
    const CompositeOptions& mOptions;
    StreamOutput mOutput;
    int mWidth, mHeight, mTilesX;
    std::vector<std::unique_ptr<TileCompositor<C>>> mTiles;
    tbb::enumerable_thread_specific<std::vector<Ring>> mSpares; ///< each thread's rings lent between tiles
    std::vector<std::uint8_t> mOpaque;
    std::vector<std::uint64_t> mSkipped; ///< pairs skipped once the tile was opaque
    std::vector<std::uint8_t> mWritten;  ///< the tile is written to the output (and let go)
};

template <int C>
std::unique_ptr<SlabStream> TileSweepCompositor<C>::stream(const CompositeOptions& options, const StreamOutput& output) const
{
    return std::make_unique<TileSweepStream<C>>(options, output);
}

template <int C>
void TileSweepCompositor<C>::composite(const SplatSet& set, const TileBins& bins, const CompositeOptions& options,
    const std::vector<float>& depthScale, Frame& frame, std::vector<TileDeep>& deep, std::vector<TileCounters>& counters,
    Progress* progress) const
{
    const int width = frame.beauty.width, height = frame.beauty.height;
    const int tiles = bins.tilesX * bins.tilesY;
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
        for (int t = range.begin(); t < range.end(); ++t) {
            const int tx = t % bins.tilesX, ty = t / bins.tilesX;
            const int x0 = tx * kTileSize, y0 = ty * kTileSize;
            const int w = std::min(kTileSize, width - x0), h = std::min(kTileSize, height - y0);
            // Indices arrive in (first slab, kernel index) order (sweepOrder).
            const std::uint32_t* order = bins.indices.data() + bins.offsets[t];
            const std::size_t count = std::size_t(bins.offsets[t + 1] - bins.offsets[t]);
            TileCompositor<C> tile(x0, y0, w, h, ringSizeFor(std::max(bins.maxSpan[std::size_t(t)], 1u)), options);
            tile.planLevel(set, order, count);
            std::size_t done = 0;
            const std::size_t passFloats = std::size_t(set.passSourceCount) * 3;
            for (; done < count && !tile.opaque(); ++done) {
                // The list jumps across the splat array (depth order): fetch ahead.
                if (done + 4 < count) __builtin_prefetch(&set.splats[order[done + 4]]);
                if (done + 2 < count) {
                    const Splat& ahead = set.splats[order[done + 2]];
                    __builtin_prefetch(set.shares.data() + ahead.shareOffset);
                    __builtin_prefetch(set.shareMoments.data() + 2 * ahead.shareOffset);
                }
                const Splat& s = set.splats[order[done]];
                tile.add(s, set.shares.data() + s.shareOffset, set.shareMoments.data() + 2 * s.shareOffset,
                    passFloats ? set.passSources.data() + order[done] * passFloats : nullptr,
                    set.shifts.empty() ? nullptr : set.shifts.data() + 3 * std::size_t(order[done]));
            }
            tile.finish(frame, depthScale, deep.empty() ? nullptr : &deep[std::size_t(t)]);
            counters[std::size_t(t)] = tile.counters(count - done);
            advance(progress);
        }
    });
}

