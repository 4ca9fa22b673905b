/// @file path_tracer.cpp
#include "reference/path_tracer.h"

#include "reference/halton_points.h"

#include "shading/shading.h"
#include "source/source.h"
#include "support/blank_frame.h"
#include "support/empty_space.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/error.h>
#include <vdb_ewa/slab_share.h>

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace vdb_ewa {
namespace detail {
namespace {

/// A path's own random numbers in [0, 1): SplitMix64 seeded from the pixel, the path and the
/// channel pass, so the image does not depend on the thread count.
class PathRandom
{
public:
    PathRandom(int x, int y, int path, int pass)
        : mState(std::uint64_t(std::uint32_t(x)) * 0x9E3779B97F4A7C15ull ^ std::uint64_t(std::uint32_t(y)) * 0xC2B2AE3D27D4EB4Full ^
                 std::uint64_t(std::uint32_t(path)) * 0x165667B19E3779F9ull ^ std::uint64_t(pass) * 0xD6E8FEB86659FD93ull)
    {
    }
    double next()
    {
        std::uint64_t z = (mState += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        z ^= z >> 31;
        return double(z >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t mState;
};

/// Path @a i's place in pixel (@a x, @a y): a Halton point rotated by the pixel's own PathRandom.
Vec2d pixelPoint(int x, int y, int i)
{
    PathRandom r(x, y, -1, 7);
    const double r0 = r.next(), r1 = r.next();
    return rotatedHalton(i, r0, r1);
}

/// A unit vector whose cosine with unit @a axis is @a cosTheta, at azimuth 2 pi @a u.
Vec3d aroundAxis(const Vec3d& axis, double cosTheta, double u)
{
    const Vec3d helper = std::abs(axis.x) < 0.9 ? Vec3d(1.0, 0.0, 0.0) : Vec3d(0.0, 1.0, 0.0);
    const Vec3d e1 = glm::normalize(glm::cross(axis, helper)), e2 = glm::cross(axis, e1);
    const double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
    const double phi = 2.0 * 3.14159265358979323846 * u;
    return glm::normalize(cosTheta * axis + sinTheta * (std::cos(phi) * e1 + std::sin(phi) * e2));
}

/// One thread's view of the medium: the density (trilinear, below --cutoff none), its colour,
/// the lights' shadows, and tracking through it in world units.
class Medium
{
public:
    /// @a progress: checked every 4,096 tracking steps (a dense voxel makes a path take millions).
    Medium(const GridSource::Impl& grid, const RenderSettings& settings, double majorantDensity, Progress* progress)
        : mGrid(grid), mSettings(settings), mModel(settings), mAccessor(grid.field->getConstAccessor()), mColor(grid),
          mTinted(bool(grid.color)), mMajorantDensity(majorantDensity), mProgress(progress)
    {
        mFromWorld = glm::inverse(grid.indexToWorldLinear);
        for (std::size_t l = 0; l < settings.lights.size(); ++l) {
            if (!mModel.dark(l)) mLights.push_back(l);
        }
        for (std::size_t l = 0; l < settings.pointLights.size(); ++l) {
            if (!mModel.pointDark(l)) mPointLights.push_back(l);
        }
        const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
        mBoxMin = Vec3d(box.min().x(), box.min().y(), box.min().z()) - 1.0;
        mBoxMax = Vec3d(box.max().x(), box.max().y(), box.max().z()) + 1.0;
    }

    const OpticalModel& model() const { return mModel; }

    double density(const Vec3d& pWorld)
    {
        // The field's values reach kMaxDensity (1e6), the global majorant with them: a cancel is
        // seen between steps, not only between pixels.
        if (mProgress && (++mSteps & 4095u) == 0) mProgress->check();
        const Vec3d q = mFromWorld * (pWorld - mGrid.indexToWorldOffset);
        float d = 0.0f;
        openvdb::tools::BoxSampler::sample(mAccessor, openvdb::Vec3d(q.x, q.y, q.z), d);
        return d >= mSettings.cutoff && d > 0.0f ? double(d) : 0.0;
    }

    /// The material colour at @a pWorld in the working space (1 without a colour grid).
    Vec3d color(const Vec3d& pWorld) { return mTinted ? workingColor(mSettings.inputToWorking, mColor.at(pWorld)) : Vec3d(1.0); }

    /// The world distances [t0, t1) along the ray where the medium may be (the padded active box).
    bool clip(const Vec3d& o, const Vec3d& d, double& t0, double& t1) const
    {
        const Vec3d oIndex = mFromWorld * (o - mGrid.indexToWorldOffset), dIndex = mFromWorld * d;
        if (!boxClip(oIndex, dIndex, mBoxMin, mBoxMax, t0, t1)) return false;
        t0 = std::max(t0, 0.0);
        return t1 > t0;
    }

    /// Delta tracking for extinction @a sigma (per voxel length per unit density): the world
    /// distance of the first real collision along the ray from @a o along unit @a d within
    /// [0, @a tMax), or a negative value where it leaves.
    double collide(const Vec3d& o, const Vec3d& d, double sigma, PathRandom& random)
    {
        double t0, t1;
        if (!clip(o, d, t0, t1)) return -1.0;
        const double majorant = sigma * mMajorantDensity / mGrid.voxelLength; // per world unit
        if (!(majorant > 0.0)) return -1.0;
        for (double t = t0;;) {
            t -= std::log(1.0 - random.next()) / majorant;
            if (t >= t1) return -1.0;
            if (random.next() * mMajorantDensity < density(o + t * d)) return t;
        }
    }

    /// Ratio tracking: the transmittance for extinction @a sigma along the ray from @a o along
    /// unit @a d, out of the medium or to world distance @a tMax (unbiased: below 1e-3 it goes
    /// on by Russian roulette).
    double transmittance(const Vec3d& o, const Vec3d& d, double sigma, PathRandom& random, double tMax = HUGE_VAL)
    {
        double t0, t1;
        if (!clip(o, d, t0, t1)) return 1.0;
        t1 = std::min(t1, tMax);
        const double majorant = sigma * mMajorantDensity / mGrid.voxelLength;
        if (!(majorant > 0.0)) return 1.0;
        double transmitted = 1.0;
        for (double t = t0;;) {
            t -= std::log(1.0 - random.next()) / majorant;
            if (t >= t1) return transmitted;
            transmitted *= 1.0 - density(o + t * d) / mMajorantDensity;
            if (transmitted < 1e-3) {
                if (random.next() >= 0.5) return 0.0;
                transmitted *= 2.0;
            }
        }
    }

    /// The world distance along the ray from @a o along unit @a d at which its mean
    /// transmittance over R, G, B falls to a half (the Z pass, as the raymarch reference finds
    /// it: steps of --step voxel lengths, midpoint density, the crossing within a step by
    /// halfAlphaFraction), or infinity.
    double halfOpacity(const Vec3d& o, const Vec3d& d)
    {
        double t0, t1;
        if (!clip(o, d, t0, t1)) return HUGE_VAL;
        const double ds = mSettings.step * mGrid.voxelLength;
        double T[3] = {1.0, 1.0, 1.0};
        for (double s = t0; s < t1; s += ds) {
            const double rho = density(o + (s + 0.5 * ds) * d);
            if (!(rho > 0.0)) continue;
            const float before = float((T[0] + T[1] + T[2]) / 3.0);
            for (int c = 0; c < 3; ++c) T[c] *= std::exp(-mModel.opticalDepth(c, rho, mSettings.step));
            const float after = float((T[0] + T[1] + T[2]) / 3.0);
            if (after <= 0.5f) {
                const double u = halfAlphaFraction(before, after);
                return u <= 1.0 ? s + u * ds : HUGE_VAL;
            }
        }
        return HUGE_VAL;
    }

    /// Next-event estimation at @a pWorld for a path that arrived along unit @a d, traced with
    /// extinction @a sigma: the light of every directional, point and spot light scattered back
    /// along -d per unit optical depth, per unit scattering albedo x colour (OpticalModel's
    /// scales, the phase function relative to isotropic), shadowed by exp(-optical depth),
    /// estimated by ratio tracking (unbiased, where vdb_render's march is not: it drops half a
    /// --shadowstep of optical depth).
    Vec3d direct(const Vec3d& pWorld, const Vec3d& d, double g, double sigma, PathRandom& random)
    {
        Vec3d sum(0.0);
        for (const std::size_t l : mLights) {
            const Vec3d towards = mSettings.lights[l].unitDirection();
            const double phase = henyeyGreenstein(glm::dot(towards, d), g);
            if (!(phase > 0.0)) continue;
            const double t = transmittance(pWorld, towards, sigma, random);
            for (int c = 0; c < 3; ++c) sum[c] += mModel.lightScale(l, c) * phase * t;
        }
        for (const std::size_t l : mPointLights) {
            const PointLight& light = mSettings.pointLights[l];
            const double falloff = pointLightFalloff(light, pWorld, mGrid.voxelLength);
            if (!(falloff > 0.0)) continue;
            const Vec3d towards = light.position - pWorld;
            const double length = glm::length(towards);
            const Vec3d unit = length > 0.0 ? towards / length : d;
            const double phase = henyeyGreenstein(glm::dot(unit, d), g);
            const double t = transmittance(pWorld, unit, sigma, random, length);
            for (int c = 0; c < 3; ++c) sum[c] += mModel.pointScale(l, c) * phase * falloff * t;
        }
        return sum;
    }

private:
    const GridSource::Impl& mGrid;
    const RenderSettings& mSettings;
    OpticalModel mModel;
    openvdb::FloatGrid::ConstAccessor mAccessor;
    MaterialColor mColor;
    bool mTinted;
    double mMajorantDensity;
    Progress* mProgress;
    std::uint64_t mSteps = 0;
    Mat3d mFromWorld{1.0};
    Vec3d mBoxMin{0.0}, mBoxMax{0.0};
    std::vector<std::size_t> mLights, mPointLights; ///< the lights and point lights that are not dark
};

/// One path from the eye along unit @a d from @a o, traced with extinction @a sigma (the
/// channels of @a channels share it): the radiance it brings back per channel (the others 0).
Vec3d tracePath(Medium& medium, const RenderSettings& settings, Vec3d o, Vec3d d, double sigma, const bool (&channels)[3], PathRandom& random)
{
    const OpticalModel& model = medium.model();
    const double g = settings.scattering.anisotropy;
    Vec3d radiance(0.0), throughput(0.0);
    for (int c = 0; c < 3; ++c) throughput[c] = channels[c] ? 1.0 : 0.0;
    for (int vertex = 0; vertex <= settings.bounces; ++vertex) {
        const double t = medium.collide(o, d, sigma, random);
        if (t < 0.0) break;
        const Vec3d x = o + t * d;
        // A real collision: the source per unit optical depth there (the estimator of the
        // integral of T sigma_t S along the segment), then the path scatters on with the albedo.
        const Vec3d color = medium.color(x);
        Vec3d albedo(0.0);
        for (int c = 0; c < 3; ++c) {
            const double extinction = model.extinction(c);
            albedo[c] = extinction > 0.0 ? settings.medium.scatter[c] / extinction * color[c] : 0.0;
            radiance[c] += throughput[c] * model.emitted(c);
        }
        const Vec3d direct = medium.direct(x, d, g, sigma, random);
        for (int c = 0; c < 3; ++c) radiance[c] += throughput[c] * color[c] * direct[c];
        // The ambient light, a uniform environment: along a direction drawn from the phase,
        // times the transmittance out of the medium that way.
        const Vec3d next = aroundAxis(d, sampleHenyeyGreenstein(g, random.next()), random.next());
        if (settings.ambient != Vec3d(0.0)) {
            const double out = medium.transmittance(x, next, sigma, random);
            for (int c = 0; c < 3; ++c) radiance[c] += throughput[c] * albedo[c] * settings.ambient[c] * out;
        }
        throughput *= albedo;
        if (throughput == Vec3d(0.0)) break;
        o = x;
        d = next;
    }
    return radiance;
}

} // namespace

Frame pathTrace(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& asked, const PassRequest& passes,
    RenderStats& stats, Progress* progress)
{
    if (grid.grid->getGridClass() == openvdb::GRID_LEVEL_SET) throw ValueError("--method pathtrace renders fog volumes; level sets are rendered with --method splat");
    if (!grid.linear) throw ValueError("--method pathtrace needs an affine grid transform (this grid has a frustum map)");
    if (grid.emission || grid.temperature) throw ValueError("--method pathtrace has no emission grids (--emission-grid, --temperature): use --method splat or raymarch");
    if (grid.velocity && asked.motionBlur.shutterClose > asked.motionBlur.shutterOpen) {
        throw ValueError("--method pathtrace renders still frames: motion blur (--velocity-grid) needs --method splat or raymarch");
    }
    if (camera.lensRadius() > 0.0) throw ValueError("--method pathtrace renders pinhole frames: --fstop needs --method splat or raymarch");
    if (passes.shadow || passes.emission || passes.deep) {
        throw ValueError("--method pathtrace renders the beauty, Z and transmittance only (shadow, emission and deep passes need --method splat)");
    }
    if (asked.scattering.octaves > 1) {
        stats.warnings.push_back("--multiple-scattering changes nothing with --method pathtrace: its paths scatter up to --bounces times");
    }
    const auto t0 = std::chrono::steady_clock::now();
    stats.activeVoxels = grid.activeVoxels;
    stats.activeTiles = grid.activeTiles;
    RenderSettings settings = asked;
    settings.shadow.gain = 0.0; // physical shadows, Cycles' law
    const int width = camera.width(), height = camera.height();
    Frame frame = blankFrame(width, height, passes);
    float lowest = 0.0f, highest = 0.0f;
    grid.field->evalMinMax(lowest, highest);
    if (!(highest > 0.0f) || grid.field->activeVoxelCount() == 0) return frame;
    // Trilinear interpolation never exceeds its largest corner: the largest voxel is a majorant.
    const double majorant = double(highest);
    // Channels that share an extinction share their paths.
    const OpticalModel model(settings);
    std::vector<std::array<bool, 3>> passGroups;
    bool done[3] = {false, false, false};
    for (int c = 0; c < 3; ++c) {
        if (done[c]) continue;
        std::array<bool, 3> group{false, false, false};
        for (int k = c; k < 3; ++k) {
            if (!done[k] && model.extinction(k) == model.extinction(c)) group[std::size_t(k)] = done[k] = true;
        }
        passGroups.push_back(group);
    }
    const int samples = settings.pathSamples;
    const Vec3d forward = glm::transpose(camera.cameraFromWorld())[2];
    setUnits(progress, std::uint64_t(height));
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        Medium medium(grid, settings, majorant, progress);
        for (int y = rows.begin(); y < rows.end(); ++y) {
            advance(progress);
            for (int x = 0; x < width; ++x) {
                if (progress) progress->check();
                Vec3d sum(0.0), transmitted(0.0);
                for (int i = 0; i < samples; ++i) {
                    const Vec2d at = Vec2d(x, y) + pixelPoint(x, y, i);
                    Vec3d origin, dir;
                    camera.worldRay(at.x, at.y, origin, dir);
                    dir = glm::normalize(dir);
                    for (std::size_t k = 0; k < passGroups.size(); ++k) {
                        const bool channels[3] = {passGroups[k][0], passGroups[k][1], passGroups[k][2]};
                        int first = 0;
                        while (!channels[first]) ++first;
                        const double sigma = model.extinction(first);
                        PathRandom random(x, y, i, int(k));
                        const double t = medium.transmittance(origin, dir, sigma, random);
                        sum += tracePath(medium, settings, origin, dir, sigma, channels, random);
                        for (int c = 0; c < 3; ++c) {
                            if (channels[c]) transmitted[c] += t;
                        }
                    }
                }
                float* px = frame.beauty.pixel(x, y);
                for (int c = 0; c < 3; ++c) px[c] = float(sum[c] / double(samples));
                const Vec3d T = transmitted / double(samples);
                px[3] = float(1.0 - (T.x + T.y + T.z) / 3.0);
                const std::size_t p = std::size_t(y) * std::size_t(width) + std::size_t(x);
                if (passes.depth) {
                    // The pixel centre's ray, as the raymarch reference's Z.
                    Vec3d origin, dir;
                    camera.worldRay(x + 0.5, y + 0.5, origin, dir);
                    dir = glm::normalize(dir);
                    const double s = medium.halfOpacity(origin, dir);
                    frame.depth[p] = std::isfinite(s) ? float(camera.near() + s * glm::dot(dir, forward)) : std::numeric_limits<float>::infinity();
                }
                if (passes.transmittance) {
                    for (int c = 0; c < 3; ++c) frame.transmittance[3 * p + std::size_t(c)] = float(T[c]);
                }
            }
        }
    });
    stats.rasterSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
