/// @file light_map.h
/// @brief A light's transmittance anywhere in the volume: a deep shadow map for one
///        directional light (Lokovic and Veach 2000). Shadow rays are marched once, from a
///        lattice of points spaced --shadow-res voxel lengths apart across the light, through
///        the whole volume, keeping the optical depth at every --shadowstep along each ray.
///        A lookup is exact along the light (to the step) and bilinear across it, in optical
///        depth: what per-sample shadow rays give, at the cost of one march per lattice ray
///        (docs/numerics.md#shading-per-slab-sample).
#pragma once

#include "shading/optical_model.h"
#include "source/source.h"
#include "support/huge_page_allocator.h"
#include "support/progress.h"

#include <vdb_ewa/render_settings.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// vdb_render's shadow-sample weight 1 / (1 + g k) at k = 1 .. K steps from the shaded point
/// (g = gain x step, in voxel lengths) as a sum of exponentials sum_n a_n decay_n^k: the
/// trapezoidal rule on 1 / (1 + x) = int exp(t - e^t (1 + x)) dt, in u = t + ln g, where
/// 1 / (1 + g k) = int exp(u - ln g - e^u (1/g + k)) du. The nodes cover only the u that
/// weigh on k in [1, K], so the number of terms is (ln K + 15.6) / 0.8 at most whatever the
/// gain (1e-300 or 1e308), exact to about 1e-4 relative. Terms whose weight a_n is below the
/// smallest normal double are left out (a gain so large that no sample at one step weighs).
struct ExponentialSum
{
    std::vector<double> a, decay;
    /// @param gainPerStep g = gain x step (infinity is taken as the largest double; a g that
    ///        changes no weight over K steps by 1e-8, g K <= 1e-8, gives the one term 1, as 0
    ///        and denormal gains do)
    /// @param steps K, the longest distance in steps (>= 1)
    ExponentialSum(double gainPerStep, double steps);
    /// The sum at @a k steps (k >= 1): about 1 / (1 + g k).
    double operator()(double k) const;
};

/// The light map's budget in lattice points (rays x steps along them), and a sixteenth of it
/// in rays. A finer --shadowstep or --shadow-res than a grid's extent allows within it is
/// raised, both by the same factor (LightMap::shadowStep, shadowResolution). Pig at --quality
/// high holds 1.7e8 points.
constexpr double kLightMapPointBudget = 2e8;

/// The unit-extinction optical depth D at which vdb_render stops a shadow ray: where
/// |T|^2 = sum_c exp(-2 extinction_c D) falls to @a cutoff (infinity where it never does, 0
/// where it starts below). The light it keeps there lights every deeper point.
double shadowStopDepth(const float* extinction, double cutoff);

/// The eight corners of the active box @a box padded by a voxel (the trilinear field's
/// support), in world space: what the light maps' lattices must cover.
std::array<Vec3d, 8> paddedBoxCorners(const GridSource::Impl& grid, const openvdb::CoordBBox& box);

class LightMap
{
public:
    /// March the lattice rays of settings.lights[@a light] through @a grid's field (which must
    /// outlive the map). @a progress: one unit per block of kRayBlock x kRayBlock rays; throws
    /// Cancelled. @a onDemand: march none yet; a tile of rays is marched when a lookup first
    /// needs it (ensureMarched; light on demand, docs/architecture.md#light-on-demand), and
    /// @a progress, which must then outlive the map, is checked for cancellation meanwhile.
    LightMap(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light = 0, Progress* progress = nullptr,
        double pointBudget = kLightMapPointBudget, bool onDemand = false);

    /// Lattice points (rays x steps) the map of settings.lights[@a light] takes within
    /// @a pointBudget, before any is marched: 0 for a dark light or an empty grid.
    static double plannedPoints(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light,
        double pointBudget = kLightMapPointBudget);

    /// Rays are marched on demand in square tiles of this many rays a side: the lookups of
    /// the shared assets at 1080p read 78-91 % of the rays marched (63-82 % with tiles of 8,
    /// 39-74 % with 16; docs/performance.md#light-rays-marched-against-looked-up), and the
    /// whole map in blocks of kRayBlock a side (tiles of 4 march it a quarter slower).
    static constexpr int kRayTile = 4;
    static constexpr int kRayBlock = 16;
    /// The rays are marched on demand (ensureMarched), not all at construction.
    bool onDemand() const { return mOnDemand; }
    /// Light on demand: march every tile holding a ray that a lookup in the map-coordinate box
    /// [@a lo, @a hi] (u and v; w is not used) reads, unless it is marched already, on the
    /// calling thread. Thread-safe, also against lookups of rays already marched: a ray's
    /// samples do not depend on which other rays are marched, or when or where, so the map
    /// looks up what the whole map holds. A thread's lookups must lie in boxes it ensured.
    /// Throws Cancelled (the progress given at construction), BudgetError.
    void ensureMarched(const Vec3d& lo, const Vec3d& hi) const;
    /// Whether every ray that a lookup in the box [@a lo, @a hi] reads is marched already (as
    /// ensureMarched would leave it): always where the whole map was marched at construction.
    bool marchedIn(const Vec3d& lo, const Vec3d& hi) const;
    /// March every ray not marched yet, in parallel (a map kept on demand, then looked up where
    /// no compositor asks for its rays first: an --iso surface's kernels). Throws Cancelled.
    void marchRemaining() const;
    /// A map kept for another render (a Scene's, lib/frame_lights.h): on-demand marching now
    /// checks @a progress for cancellation, and the counters a render reports
    /// (raysMarchedBefore, marchThreadSeconds) start from here.
    void beginRender(Progress* progress);
    /// Rays marched before beginRender: by earlier renders, reused by this one.
    std::uint64_t raysMarchedBefore() const { return mRaysBefore; }
    /// Whether lattice ray (@a i, @a j) has been marched (false off the lattice).
    bool marched(int i, int j) const
    {
        if (!mMarching || i < 0 || j < 0 || i >= mNu || j >= mNv) return false;
        return mMarching->state[std::size_t(j / kRayTile) * std::size_t(mTilesU) + std::size_t(i / kRayTile)].load(std::memory_order_acquire) != 0;
    }
    /// The lattice's rays across the light (u) and along v.
    int raysU() const { return mNu; }
    int raysV() const { return mNv; }
    /// Rays marched so far, and the lattice's rays in all.
    std::uint64_t raysMarched() const { return mMarching ? mMarching->raysMarched.load() : 0; }
    std::uint64_t rays() const { return std::uint64_t(mNu) * std::uint64_t(mNv); }
    /// Thread-seconds spent marching rays so far (since beginRender), summed over the threads
    /// that marched them.
    double marchThreadSeconds() const { return mMarching ? 1e-9 * double(mMarching->nanoseconds.load()) : 0.0; }

    /// The shadow step and ray spacing used (voxel lengths): the settings', unless the budget
    /// raised them.
    double shadowStep() const { return mShadowStep; }
    double shadowResolution() const { return mShadowResolution; }
    /// Lattice points: rays x steps along them.
    double latticePoints() const { return double(mNu) * double(mNv) * double(mNw); }

    /// Map coordinates of a world point: across the light in lattice units (u, v), along it in
    /// steps (w, increasing towards the light).
    Vec3d coordinates(const Vec3d& pWorld) const { return mFromWorld * (pWorld - mOrigin); }
    /// The map coordinates' change per world unit along a direction (linear: rays stay rays).
    Vec3d direction(const Vec3d& dWorld) const { return mFromWorld * dWorld; }

    /// Shadow-ray optical depth of unit-extinction density at map coordinates @a q (the
    /// extinction of each channel multiplies it): bilinear across, linear along the light.
    float densityDepth(const Vec3d& q) const;
    /// densityDepth at two points, sharing the lattice rays when both lie in one cell (the
    /// front and back of a layer on a pixel's ray).
    void densityDepths(const Vec3d& q0, const Vec3d& q1, float& d0, float& d1) const;

    /// The light's transmittance at map coordinates @a q, with vdb_render's early stop
    /// (|T|^2 >= cutoff): without gain, the depth one sample past it, as its ray marched from
    /// the lattice point keeps it; with gain, as a floor.
    std::array<float, 3> transmittance(const Vec3d& q) const { return transmittanceOfDepth(densityDepth(q)); }

    /// The light's transmittance behind a unit-extinction optical depth @a depth (densityDepth),
    /// per channel, with the same floor.
    std::array<float, 3> transmittanceOfDepth(float depth) const;
    /// Its natural logarithm per channel: minus the optical depth where the floor does not
    /// apply, so that ln(front / back) across a layer needs no log. In a grey medium (the same
    /// extinction in R, G and B) each channel is greyLogTransmittanceOfDepth, bit for bit.
    std::array<float, 3> logTransmittanceOfDepth(float depth) const;
    /// The same where every channel's extinction is the same (the grey fast path): one value.
    float greyLogTransmittanceOfDepth(float depth) const;

    /// The map as plain arrays, for a vector lookup of densityDepth and logTransmittanceOfDepth
    /// (the SIMD rasteriser): the data and constants the scalar lookups read.
    struct Lattice
    {
        int nu = 0, nv = 0;                   ///< rays across the light; ray (i, j) at [j * nu + i]
        const std::int32_t* kLo = nullptr;    ///< per ray: sample index of its first stored sample
        const std::int32_t* count = nullptr;  ///< stored samples (0: no density on the ray)
        const std::int32_t* offset = nullptr; ///< its first stored sample in depth
        const float* depth = nullptr;         ///< null: no ray holds density (every depth 0)
        float extinction[3] = {0.0f, 0.0f, 0.0f};
        float stopDepth = 0.0f, logGreyFloor = 0.0f;
        bool grey = true;
    };
    Lattice lattice() const;

private:
    /// The tiles of rays (tu, tv) holding a ray that a lookup in the box [@a lo, @a hi] reads,
    /// in order, until @a visit returns false; false then, true otherwise (none: off the lattice).
    template <typename Visit> bool forEachTileIn(const Vec3d& lo, const Vec3d& hi, Visit&& visit) const;
    /// The lattice's frame: map coordinates of world points, the padded active box's range in
    /// them, and the ray spacing and step (voxel lengths) within the point budget.
    struct LatticeFrame
    {
        Mat3d fromWorld{1.0};
        Vec3d lo{0.0}, hi{0.0};
        double resolution = 0.0, step = 0.0;
    };
    /// None for an empty grid.
    static std::optional<LatticeFrame> latticeFrame(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light,
        double pointBudget);

    /// A lattice ray as marched (stored as mRayKLo, mRayCount, mRayOffset).
    struct Ray
    {
        std::uint64_t offset = 0; ///< first stored sample in mDepth
        std::int32_t kLo = 0;     ///< sample index of the first stored sample
        std::int32_t count = 0;   ///< stored samples; above them (towards the light) the depth is 0
    };
    /// The lattice ray (i, j), -1 outside the lattice or where it holds no density.
    int ray(int i, int j) const;
    /// Optical depth on ray @a r (or 0 if r < 0) at @a w steps along the light.
    float depthOnRay(int r, double w) const;
    /// The four lattice rays around (u, v), bilinear weights a, b: the cell densityDepth reads.
    struct Cell
    {
        int rays[4];
        float a, b;
    };
    Cell cell(const Vec3d& q) const;
    float depthInCell(const Cell& cell, double w) const;

    /// A marching thread's accessor and buffers, kept from tile to tile (light_map.cpp).
    struct MarchScratch;
    /// March tile @a t of rays (row-major, mTilesU a row) unless marched: its rays' samples
    /// into a range of mDepth of their own, then the rays' fields, then its state (release).
    void marchTile(std::size_t t, MarchScratch& scratch) const;
    /// March rays [@a i0, @a i1) x [@a j0, @a j1): their samples into a range of mDepth of
    /// their own, then their fields.
    void marchRays(int i0, int i1, int j0, int j1, MarchScratch& scratch) const;

    Mat3d mFromWorld{1.0}; ///< rows: e1 / h, e2 / h, l / step (world units)
    Vec3d mOrigin{0.0};    ///< world position of map coordinates (0, 0, 0)
    int mNu = 0, mNv = 0, mNw = 0;
    double mShadowStep = 0.0, mShadowResolution = 0.0;
    /// Per ray [j * mNu + i]: Ray's fields, one array each (LightMap::Lattice); 0 until its
    /// tile is marched. Offsets fit 32 bits: the point budget is below 2^31. Mutable, as
    /// mDepth: marching fills them in without changing what a lookup of a marched ray reads.
    mutable std::vector<std::int32_t> mRayKLo, mRayCount, mRayOffset;
    /// Room for every lattice point, touched only where marched: each tile's samples go to a
    /// range of their own, in the order the tiles are marched.
    mutable UntouchedArray<float> mDepth;
    float mExtinction[3];
    /// The lookups' floor: shadowStopDepth, where vdb_render's shadow ray stops (unit-extinction
    /// depth), and ln sqrt(cutoff / 3), a grey medium's floor (-extinction x mStopDepth); none
    /// (infinite) where the rays' samples hold the stop themselves (mStopsInRays).
    float mStopDepth;
    float mLogGreyFloor;
    /// Without gain each ray's samples hold the depth at which vdb_render's shadow ray from
    /// there stops, one sample past shadowStopDepth (stoppedDepths), not a floor.
    bool mStopsInRays = false;
    double mRayStopDepth = 0.0; ///< shadowStopDepth, for marching
    bool mGrey = true;   ///< the same extinction in R, G and B
    bool mUnlit;

    // What marching a ray needs, kept for rays marched on demand.
    const GridSource::Impl* mGrid = nullptr;
    double mCutoff = 0.0;
    std::vector<double> mWeight, mDecay; ///< ExponentialSum's terms
    int mMargin = 0;                     ///< steps kept below a ray's lowest density
    Vec3d mP0{0.0}, mDu{0.0}, mDv{0.0}, mDw{0.0}; ///< index position of lattice points (affine grids)
    Mat3d mWorldFromMap{1.0};
    int mTilesU = 0, mTilesV = 0;
    /// What marching shares between threads (held apart: atomics and locks do not move).
    struct Marching
    {
        explicit Marching(std::size_t tiles) : state(new std::atomic<std::uint8_t>[tiles]()) {}
        std::unique_ptr<std::atomic<std::uint8_t>[]> state; ///< per tile of rays: 1 once marched
        /// Held while marching a tile: tile t takes lock t % kLocks (few threads contend).
        static constexpr std::size_t kLocks = 64;
        std::mutex locks[kLocks];
        std::atomic<std::uint64_t> depthUsed{0};            ///< samples of mDepth handed out
        std::atomic<std::uint64_t> raysMarched{0};
        std::atomic<std::uint64_t> nanoseconds{0}; ///< thread-time spent marching
    };
    std::unique_ptr<Marching> mMarching;
    Progress* mProgress = nullptr;
    bool mOnDemand = false;
    std::uint64_t mRaysBefore = 0; ///< raysMarched at beginRender
};

// The lookups, inline: the rasteriser makes one per lit (pixel, slab) sample.

inline int LightMap::ray(int i, int j) const
{
    if (i < 0 || j < 0 || i >= mNu || j >= mNv) return -1;
    const int r = j * mNu + i;
    return mRayCount[std::size_t(r)] > 0 ? r : -1;
}

inline float LightMap::depthOnRay(int r, double w) const
{
    if (r < 0) return 0.0f;
    const double x = std::max(w - double(mRayKLo[std::size_t(r)]), 0.0); // below the stored range: its first value
    const int k = int(x), count = mRayCount[std::size_t(r)];
    if (k >= count) return 0.0f;
    const float* d = mDepth.data() + mRayOffset[std::size_t(r)];
    const float next = k + 1 < count ? d[k + 1] : 0.0f;
    return d[k] + float(x - double(k)) * (next - d[k]);
}

inline LightMap::Cell LightMap::cell(const Vec3d& q) const
{
    const double fu = std::floor(q.x), fv = std::floor(q.y);
    const int i = int(std::clamp(fu, -1.0, double(mNu))), j = int(std::clamp(fv, -1.0, double(mNv)));
    return {{ray(i, j), ray(i + 1, j), ray(i, j + 1), ray(i + 1, j + 1)}, float(q.x - fu), float(q.y - fv)};
}

inline float LightMap::depthInCell(const Cell& c, double w) const
{
    const float d00 = depthOnRay(c.rays[0], w), d10 = depthOnRay(c.rays[1], w);
    const float d01 = depthOnRay(c.rays[2], w), d11 = depthOnRay(c.rays[3], w);
    return (1.0f - c.b) * ((1.0f - c.a) * d00 + c.a * d10) + c.b * ((1.0f - c.a) * d01 + c.a * d11);
}

inline float LightMap::densityDepth(const Vec3d& q) const
{
    if (mRayCount.empty()) return 0.0f;
    return depthInCell(cell(q), q.z);
}

inline void LightMap::densityDepths(const Vec3d& q0, const Vec3d& q1, float& d0, float& d1) const
{
    if (mRayCount.empty()) {
        d0 = d1 = 0.0f;
        return;
    }
    Cell c = cell(q0);
    d0 = depthInCell(c, q0.z);
    if (std::floor(q0.x) == std::floor(q1.x) && std::floor(q0.y) == std::floor(q1.y)) {
        c.a = float(q1.x - std::floor(q1.x));
        c.b = float(q1.y - std::floor(q1.y));
    } else {
        c = cell(q1);
    }
    d1 = depthInCell(c, q1.z);
}

inline float LightMap::greyLogTransmittanceOfDepth(float depth) const
{
    // |T|^2 = 3 T^2 < cutoff where T < sqrt(cutoff / 3): the floor, in the log domain.
    return depth > 0.0f ? std::max(-mExtinction[0] * depth, mLogGreyFloor) : 0.0f;
}

} // namespace detail
} // namespace vdb_ewa
