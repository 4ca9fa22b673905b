/// @file light_map.cpp
#include "shading/light_map.h"

#include "support/empty_space.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace vdb_ewa {
namespace detail {

ExponentialSum::ExponentialSum(double gainPerStep, double steps)
{
    // In u = t + ln g, the integrand of 1 / (1 + g k) is exp(u - ln g - e^u (1/g + k)). Nodes
    // every eta from where e^u (1/g + K) is e^-12 (the mass left out below, relative) to where
    // e^u (1/g + 1) is 36.6 (exp(-36.6) is nothing at the nearest sample, k = 1). In logs
    // throughout: g may be 1e-300 or 1e308.
    if (!(gainPerStep * steps > 1e-8)) { // no gain, or one no weight feels: every sample weighs 1
        a.push_back(1.0);
        decay.push_back(1.0);
        return;
    }
    const double eta = 0.8;
    const double logG = std::log(std::min(gainPerStep, std::numeric_limits<double>::max()));
    // ln(1/g + x) without forming 1/g, which overflows below g = 5.6e-309 (denormal gains).
    const auto logInvGPlus = [&](double x) {
        const double a = -logG, b = std::log(x);
        return std::max(a, b) + std::log1p(std::exp(-std::abs(a - b)));
    };
    const double u0 = -logInvGPlus(std::max(steps, 1.0)) - 12.0, u1 = std::log(36.6) - logInvGPlus(1.0);
    for (double u = u0; u <= u1; u += eta) {
        const double weight = eta * std::exp(u - logG - std::exp(u - logG));
        if (!(weight >= std::numeric_limits<double>::min())) continue;
        a.push_back(weight);
        decay.push_back(std::exp(-std::exp(u)));
    }
}

double ExponentialSum::operator()(double k) const
{
    double f = 0.0;
    for (std::size_t n = 0; n < a.size(); ++n) f += a[n] * std::pow(decay[n], k);
    return f;
}

std::array<Vec3d, 8> paddedBoxCorners(const GridSource::Impl& grid, const openvdb::CoordBBox& box)
{
    std::array<Vec3d, 8> corners;
    for (int c = 0; c < 8; ++c) {
        const Vec3d p((c & 1 ? box.max().x() + 1 : box.min().x() - 1), (c & 2 ? box.max().y() + 1 : box.min().y() - 1),
            (c & 4 ? box.max().z() + 1 : box.min().z() - 1));
        corners[std::size_t(c)] = grid.indexToWorld(p);
    }
    return corners;
}

double shadowStopDepth(const float* extinction, double cutoff)
{
    // f(D) = sum_c exp(-2 sigma_c D) falls from 3 to the number of channels without
    // extinction: it crosses the cutoff once, or never.
    double never = 0.0;
    for (int c = 0; c < 3; ++c) never += extinction[c] > 0.0f ? 0.0 : 1.0;
    if (!(cutoff > never)) return std::numeric_limits<double>::infinity();
    if (cutoff >= 3.0) return 0.0;
    // Newton from D = 0: f is convex and decreasing, so every step stays short of the root.
    double depth = 0.0;
    for (int n = 0; n < 100; ++n) {
        double f = -cutoff, slope = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double e = std::exp(-2.0 * double(extinction[c]) * depth);
            f += e;
            slope -= 2.0 * double(extinction[c]) * e;
        }
        const double step = -f / slope;
        if (!(step > 1e-15 * std::max(depth, 1e-300))) break;
        depth += step;
    }
    return depth;
}

namespace {

/// Without gain: the depth at which vdb_render's shadow ray from each sample of a lattice ray
/// stops. @a tau[k] = P(k + 1), the sum of samples k + 1 .. top (0 from tau.size() on), falls
/// with k; the ray from k stops after the first m > k with tau[k] - tau[m] > @a stop and keeps
/// tau[k] - tau[m], up to one sample past the stop (not the floor at @a stop: 2.7 % too
/// bright in pyro's dense core at --shadowstep 0.375, docs/numerics.md#the-light-maps-stop).
/// As k falls tau[k] - stop grows, so that m never rises: one pointer, moved down once.
void stoppedDepths(const std::vector<double>& tau, double stop, float* out)
{
    const int count = int(tau.size());
    const auto at = [&](int m) { return m < count ? tau[std::size_t(m)] : 0.0; };
    int m = count; // the lowest m > k with at(m) < tau[k] - stop, once there is one
    for (int k = count - 1; k >= 0; --k) {
        const double limit = tau[std::size_t(k)] - stop;
        if (limit > 0.0) {
            while (m - 1 > k && at(m - 1) < limit) --m;
            out[k] = float(tau[std::size_t(k)] - at(m));
        } else {
            out[k] = float(tau[std::size_t(k)]); // shallower than the stop: the ray runs out first
        }
    }
}

} // namespace

struct LightMap::MarchScratch
{
    MarchScratch(const GridSource::Impl& grid, int steps, std::size_t terms) : skipper(*grid.field, 0), density(std::size_t(steps)), f(terms) {}
    EmptySpaceSkipper skipper;
    std::vector<double> density, f;
    std::vector<double> tau;   ///< a ray's samples before they are stored
    std::vector<float> depths; ///< a tile's samples, ray after ray
    std::vector<Ray> rays;     ///< offsets within depths
};

std::optional<LightMap::LatticeFrame> LightMap::latticeFrame(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light,
    double pointBudget)
{
    const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
    if (box.empty()) return std::nullopt;
    // Frame: e1, e2 across the light, l towards it; units h across, the step along (world
    // lengths in voxel lengths, as vdb_render's steps).
    const double ell = grid.voxelLength;
    double h = settings.shadow.resolution, step = settings.shadow.step;
    const Vec3d l = settings.lights[light].unitDirection();
    const Vec3d e1 = glm::normalize(glm::cross(l, std::abs(l.x) < 0.6 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0)));
    const Vec3d e2 = glm::cross(l, e1);
    LatticeFrame f;
    const std::array<Vec3d, 8> corners = paddedBoxCorners(grid, box);
    for (int attempt = 0;; ++attempt) {
        f.fromWorld = glm::transpose(Mat3d(e1 / (h * ell), e2 / (h * ell), l / (step * ell)));
        // The padded active box (trilinear support) in map coordinates; lattice from its corner.
        f.lo = Vec3d(1e300);
        f.hi = Vec3d(-1e300);
        for (const Vec3d& corner : corners) {
            const Vec3d q = f.fromWorld * corner;
            f.lo = glm::min(f.lo, q);
            f.hi = glm::max(f.hi, q);
        }
        // Anchored at the box's corner, not at world multiples: the lattice moves with the grid,
        // so the image does not depend on where in the world the scene is.
        f.hi = f.lo + glm::ceil(f.hi - f.lo);
        // Within the budget, or coarsened: a finer step or ray spacing than the grid's extent
        // allows is raised, both by the same factor (docs/numerics.md#the-light-maps-budget).
        const Vec3d n = f.hi - f.lo + Vec3d(1.0);
        const double scale = std::max(std::cbrt(n.x * n.y * n.z / pointBudget), std::sqrt(n.x * n.y * 16.0 / pointBudget));
        if (!(scale > 1.0) || attempt == 8) break;
        h *= 1.01 * scale;
        step *= 1.01 * scale;
    }
    f.resolution = h;
    f.step = step;
    return f;
}

double LightMap::plannedPoints(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light, double pointBudget)
{
    if (OpticalModel(settings).dark(light)) return 0.0;
    const std::optional<LatticeFrame> f = latticeFrame(grid, settings, light, pointBudget);
    if (!f) return 0.0;
    const Vec3d n = f->hi - f->lo + Vec3d(1.0);
    return n.x * n.y * n.z;
}

LightMap::LightMap(const GridSource::Impl& grid, const RenderSettings& settings, std::size_t light, Progress* progress, double pointBudget,
    bool onDemand)
    : mLogGreyFloor(0.5f * std::log(float(settings.cutoff) / 3.0f))
{
    const OpticalModel model(settings);
    for (int c = 0; c < 3; ++c) mExtinction[c] = float(model.extinction(c));
    mStopDepth = float(shadowStopDepth(mExtinction, settings.cutoff));
    mGrey = mExtinction[0] == mExtinction[1] && mExtinction[0] == mExtinction[2];
    mUnlit = model.dark(light);
    mShadowStep = settings.shadow.step;
    mShadowResolution = settings.shadow.resolution;
    setUnits(progress, 0);
    if (mUnlit) return;
    const std::optional<LatticeFrame> frame = latticeFrame(grid, settings, light, pointBudget);
    if (!frame) return;
    mFromWorld = frame->fromWorld;
    const Vec3d lo = frame->lo, hi = frame->hi;
    mShadowResolution = frame->resolution;
    mShadowStep = frame->step;
    const double step = mShadowStep;
    const Mat3d worldFromMap = glm::inverse(mFromWorld);
    mOrigin = worldFromMap * lo;
    mNu = int(hi.x - lo.x) + 1;
    mNv = int(hi.y - lo.y) + 1;
    mNw = int(hi.z - lo.z) + 1;

    // vdb_render weighs a shadow sample s voxel lengths away by 1 / (1 + gain s): as a sum of
    // exponentials, each term a first-order recursive filter along the ray (ExponentialSum).
    // No gain is the one term 1 (ExponentialSum's own case, also for a gain no weight feels).
    const ExponentialSum sum(settings.shadow.gain * step, double(mNw));
    mWeight = sum.a;
    mDecay = sum.decay;
    const bool gain = !(mWeight.size() == 1 && mDecay[0] == 1.0);
    // Without gain a ray's samples are suffix sums, and the sample at which vdb_render's ray
    // from each of them stops is found in one pass (stoppedDepths): the rays hold the stop,
    // the lookups need no floor. With gain each sample weighs by its distance from where the
    // ray starts, so the stop stays a floor at shadowStopDepth, which is up to one sample short.
    mRayStopDepth = double(mStopDepth);
    mStopsInRays = !gain && std::isfinite(mRayStopDepth);
    if (mStopsInRays) {
        mStopDepth = std::numeric_limits<float>::infinity();
        mLogGreyFloor = -std::numeric_limits<float>::infinity();
    }
    mMargin = int(std::ceil(2.0 / step)); // kept below a ray's lowest density
    mCutoff = settings.cutoff;
    mGrid = &grid;
    // Index position of lattice point (i, j, k): affine grids p0 + i du + j dv + k dw.
    mWorldFromMap = worldFromMap;
    mP0 = grid.worldToIndex(mOrigin);
    mDu = grid.worldToIndex(mOrigin + worldFromMap[0]) - mP0;
    mDv = grid.worldToIndex(mOrigin + worldFromMap[1]) - mP0;
    mDw = grid.worldToIndex(mOrigin + worldFromMap[2]) - mP0;

    const std::size_t rays = std::size_t(mNu) * std::size_t(mNv);
    mRayKLo.assign(rays, 0);
    mRayCount.assign(rays, 0);
    mRayOffset.assign(rays, 0);
    mTilesU = (mNu + kRayTile - 1) / kRayTile;
    mTilesV = (mNv + kRayTile - 1) / kRayTile;
    const std::size_t tiles = std::size_t(mTilesU) * std::size_t(mTilesV);
    mMarching = std::make_unique<Marching>(tiles);
    // Room for every lattice point (a ray stores at most mNw samples), mapped but not touched
    // until marched: tiles marched in any order, on any thread, write ranges of their own.
    mDepth = UntouchedArray<float>(std::size_t(std::min(latticePoints(), double(std::numeric_limits<std::int32_t>::max()))));
    mProgress = progress;
    mOnDemand = onDemand;
    if (onDemand) {
        // Ray 0 first: the vector lookup's lanes that look nothing up read it and discard it.
        MarchScratch scratch(grid, mNw, mWeight.size());
        marchTile(0, scratch);
        return;
    }
    // The whole map: blocks of kRayBlock x kRayBlock rays, one task each (4 x 4 tiles of rays
    // march a quarter slower: pig's light map 0.54 s against 0.41-0.50 s at 1080p).
    const int blocksU = (mNu + kRayBlock - 1) / kRayBlock, blocksV = (mNv + kRayBlock - 1) / kRayBlock;
    setUnits(progress, std::size_t(blocksU) * std::size_t(blocksV));
    tbb::parallel_for(tbb::blocked_range<int>(0, blocksU * blocksV, 1), [&](const tbb::blocked_range<int>& range) {
        MarchScratch scratch(grid, mNw, mWeight.size());
        for (int b = range.begin(); b < range.end(); ++b) {
            const int bu = b % blocksU, bv = b / blocksU;
            marchRays(bu * kRayBlock, std::min((bu + 1) * kRayBlock, mNu), bv * kRayBlock, std::min((bv + 1) * kRayBlock, mNv), scratch);
            advance(progress);
        }
    });
    for (std::size_t t = 0; t < tiles; ++t) mMarching->state[t].store(1, std::memory_order_relaxed);
}

template <typename Visit> bool LightMap::forEachTileIn(const Vec3d& lo, const Vec3d& hi, Visit&& visit) const
{
    if (!(hi.x >= 0.0 && hi.y >= 0.0 && lo.x <= double(mNu) && lo.y <= double(mNv))) return true; // off the lattice: no density
    // The bilinear lookup reads the rays at floor(u) and floor(u) + 1.
    const auto first = [](double x, int n) { return int(std::clamp(std::floor(x), 0.0, double(n - 1))) / kRayTile; };
    const auto last = [](double x, int n) { return int(std::clamp(std::floor(x) + 1.0, 0.0, double(n - 1))) / kRayTile; };
    for (int tv = first(lo.y, mNv); tv <= last(hi.y, mNv); ++tv)
        for (int tu = first(lo.x, mNu); tu <= last(hi.x, mNu); ++tu)
            if (!visit(std::size_t(tv) * std::size_t(mTilesU) + std::size_t(tu))) return false;
    return true;
}

void LightMap::ensureMarched(const Vec3d& lo, const Vec3d& hi) const
{
    if (!mMarching) return;
    std::unique_ptr<MarchScratch> scratch; // made at the first tile to march
    forEachTileIn(lo, hi, [&](std::size_t t) {
        if (mMarching->state[t].load(std::memory_order_acquire)) return true;
        if (!scratch) scratch = std::make_unique<MarchScratch>(*mGrid, mNw, mWeight.size());
        marchTile(t, *scratch);
        return true;
    });
}

void LightMap::marchRemaining() const
{
    if (!mMarching) return;
    // Its time is the caller's (the shadows' stage), not light on demand's (marchThreadSeconds).
    const std::uint64_t nanoseconds = mMarching->nanoseconds.load();
    const std::size_t tiles = std::size_t(mTilesU) * std::size_t(mTilesV);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 16), [&](const tbb::blocked_range<std::size_t>& range) {
        std::unique_ptr<MarchScratch> scratch;
        for (std::size_t t = range.begin(); t < range.end(); ++t) {
            if (mMarching->state[t].load(std::memory_order_acquire)) continue;
            if (!scratch) scratch = std::make_unique<MarchScratch>(*mGrid, mNw, mWeight.size());
            marchTile(t, *scratch);
        }
    });
    mMarching->nanoseconds.store(nanoseconds);
}

void LightMap::beginRender(Progress* progress)
{
    mProgress = progress;
    if (!mMarching) return;
    mRaysBefore = mMarching->raysMarched.load();
    mMarching->nanoseconds.store(0);
}

bool LightMap::marchedIn(const Vec3d& lo, const Vec3d& hi) const
{
    if (!mMarching) return true;
    return forEachTileIn(lo, hi, [&](std::size_t t) { return mMarching->state[t].load(std::memory_order_acquire) != 0; });
}

void LightMap::marchTile(std::size_t t, MarchScratch& scratch) const
{
    Marching& marching = *mMarching;
    // Another thread marching this tile holds its lock until the rays are in place.
    const std::lock_guard<std::mutex> lock(marching.locks[t % Marching::kLocks]);
    if (marching.state[t].load(std::memory_order_acquire)) return;
    const auto start = std::chrono::steady_clock::now();
    const int tu = int(t % std::size_t(mTilesU)), tv = int(t / std::size_t(mTilesU));
    marchRays(tu * kRayTile, std::min((tu + 1) * kRayTile, mNu), tv * kRayTile, std::min((tv + 1) * kRayTile, mNv), scratch);
    marching.nanoseconds += std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - start).count());
    marching.state[t].store(1, std::memory_order_release);
}

void LightMap::marchRays(int i0, int i1, int j0, int j1, MarchScratch& scratch) const
{
    Marching& marching = *mMarching;
    const GridSource::Impl& grid = *mGrid;
    const int terms = int(mWeight.size());
    const auto indexAt = [&](int i, int j, int k) {
        return grid.linear ? mP0 + double(i) * mDu + double(j) * mDv + double(k) * mDw
                           : grid.worldToIndex(mOrigin + mWorldFromMap * Vec3d(i, j, k));
    };
    EmptySpaceSkipper& skipper = scratch.skipper;
    std::vector<double>& density = scratch.density;
    std::vector<double>& f = scratch.f;
    std::vector<float>& depths = scratch.depths;
    std::vector<Ray>& rays = scratch.rays;
    depths.clear();
    rays.clear();
    for (int j = j0; j < j1; ++j) {
        if (mProgress) mProgress->check();
        for (int i = i0; i < i1; ++i) {
            int kTop = -1, kBottom = -1; // samples holding density
            for (int k = mNw - 1; k >= 0; --k) {
                const Vec3d p = indexAt(i, j, k);
                // In an empty node, every sample before the ray leaves it (p - t dw, t < exit) is 0.
                const double exit = grid.linear ? skipper.emptyExit(p, -mDw) : 0.0;
                if (exit > 0.0) {
                    const int empty = int(std::min(std::ceil(exit), double(k + 1)));
                    std::fill_n(density.begin() + (k + 1 - empty), empty, 0.0);
                    k -= empty - 1;
                    continue;
                }
                double d = 0.0;
                float v = 0.0f;
                openvdb::tools::BoxSampler::sample(skipper.accessor(), openvdb::Vec3d(p.x, p.y, p.z), v);
                if (v >= mCutoff) d = v; // vdb_render skips samples below its cutoff
                density[std::size_t(k)] = d;
                if (d > 0.0) {
                    if (kTop < 0) kTop = k;
                    kBottom = k;
                }
            }
            Ray ray;
            if (kTop >= 0) {
                // Stored: from a margin below the lowest density up to just below the highest
                // (above it the depth is 0). Filtered from the light side down over that range
                // only: depth(k) = sum_n a_n F_n(k), F_n(k) = decay_n (F_n(k + 1) + d(k + 1) step).
                ray.kLo = std::max(0, kBottom - mMargin);
                ray.count = std::max(0, kTop - ray.kLo);
                ray.offset = depths.size();
                depths.resize(depths.size() + std::size_t(ray.count));
                float* depth = depths.data() + ray.offset;
                std::fill(f.begin(), f.end(), 0.0);
                std::vector<double>& tauOf = scratch.tau;
                tauOf.resize(std::size_t(ray.count));
                for (int k = kTop; k >= ray.kLo; --k) {
                    if (k < kTop) {
                        double tau = 0.0;
                        for (int n = 0; n < terms; ++n) tau += mWeight[std::size_t(n)] * f[std::size_t(n)];
                        tauOf[std::size_t(k - ray.kLo)] = tau;
                    }
                    const double d = density[std::size_t(k)];
                    for (int n = 0; n < terms; ++n) f[std::size_t(n)] = mDecay[std::size_t(n)] * (f[std::size_t(n)] + d * mShadowStep);
                }
                if (mStopsInRays) {
                    stoppedDepths(tauOf, mRayStopDepth, depth);
                } else {
                    for (int k = 0; k < ray.count; ++k) depth[k] = float(tauOf[std::size_t(k)]);
                }
            }
            rays.push_back(ray);
        }
    }
    // The tile's range of mDepth. A ray stores at most mNw samples, so the lattice's room holds
    // them all unless the room was capped at 2^31 samples (mRayOffset's 32 bits).
    const std::uint64_t base = marching.depthUsed.fetch_add(depths.size());
    if (base + depths.size() > mDepth.size()) {
        throw BudgetError("the light map would hold more than " + std::to_string(mDepth.size()) + " samples; raise --shadowstep or --shadow-res");
    }
    std::copy(depths.begin(), depths.end(), mDepth.data() + base);
    std::size_t n = 0;
    for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i) {
            const Ray& ray = rays[n++];
            const std::size_t r = std::size_t(j) * std::size_t(mNu) + std::size_t(i);
            mRayKLo[r] = ray.kLo;
            mRayCount[r] = ray.count;
            mRayOffset[r] = std::int32_t(base + ray.offset);
        }
    marching.raysMarched += n;
}

LightMap::Lattice LightMap::lattice() const
{
    Lattice l;
    l.nu = mNu;
    l.nv = mNv;
    if (!mRayCount.empty()) {
        l.kLo = mRayKLo.data();
        l.count = mRayCount.data();
        l.offset = mRayOffset.data();
        l.depth = mDepth.data();
    }
    std::copy(std::begin(mExtinction), std::end(mExtinction), l.extinction);
    l.stopDepth = mStopDepth;
    l.logGreyFloor = mLogGreyFloor;
    l.grey = mGrey;
    return l;
}

std::array<float, 3> LightMap::logTransmittanceOfDepth(float depth) const
{
    std::array<float, 3> logT{0.0f, 0.0f, 0.0f};
    if (mGrey) {
        // The grey path's value in every channel: bit-identical to it by construction.
        logT.fill(greyLogTransmittanceOfDepth(depth));
        return logT;
    }
    if (!(depth > 0.0f)) return logT;
    // vdb_render stops a shadow ray where |T|^2 falls below the cutoff and keeps the
    // transmittance it had there: every deeper point sees the light of the stop depth.
    const float kept = std::min(depth, mStopDepth);
    for (std::size_t c = 0; c < 3; ++c) logT[c] = -mExtinction[c] * kept;
    return logT;
}

std::array<float, 3> LightMap::transmittanceOfDepth(float depth) const
{
    std::array<float, 3> t = logTransmittanceOfDepth(depth);
    for (float& v : t) v = std::exp(v);
    return t;
}

} // namespace detail
} // namespace vdb_ewa
