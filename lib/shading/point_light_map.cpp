/// @file point_light_map.cpp
#include "shading/point_light_map.h"

#include "shading/light_map.h"

#include "support/empty_space.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/slab_share.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {

namespace {

/// The spot's cone at @a d from the light (|d| = @a r > 0): 1 inside, 0 outside, smoothstep in
/// the cosine across the blend.
double spotFactor(const PointLight& light, const Vec3d& d, double r)
{
    if (!(light.spotAngle > 0.0)) return 1.0;
    if (!(r > 0.0)) return 1.0; // at the apex: lit, as the nearest points are
    const double cosine = glm::dot(d, glm::normalize(light.spotTarget - light.position)) / r;
    const double cosEdge = std::cos(0.5 * light.spotAngle * 3.14159265358979323846 / 180.0);
    if (!(cosine > cosEdge)) return 0.0;
    const double smooth = (1.0 - cosEdge) * light.spotBlend;
    if (!(cosine - cosEdge < smooth)) return 1.0;
    const double x = (cosine - cosEdge) / smooth;
    return x * x * (3.0 - 2.0 * x);
}

double coreRadius(const PointLight& light, double voxelLength) { return std::max(light.radius, 0.5 * voxelLength); }

} // namespace

double pointLightFalloff(const PointLight& light, const Vec3d& p, double voxelLength)
{
    const Vec3d d = p - light.position;
    const double r = glm::length(d), core = coreRadius(light, voxelLength);
    return spotFactor(light, d, r) / (r * r + core * core);
}

double pointShadowDepth(const GridSource::Impl& grid, openvdb::FloatGrid::ConstAccessor& accessor, const Vec3d& pIndex,
    const Vec3d& lightWorld, double step, double cutoff, const Vec3d& boxMin, const Vec3d& boxMax)
{
    // In world units from the point towards the light, clipped to the box (linear grids: the
    // segment is a segment in index space too; otherwise each sample is mapped).
    const Vec3d pWorld = grid.indexToWorld(pIndex);
    const Vec3d toLight = lightWorld - pWorld;
    const double length = glm::length(toLight);
    if (!(length > 0.0)) return 0.0;
    const Vec3d dir = toLight / length;
    const Vec3d dIndex = grid.linear ? glm::inverse(grid.indexToWorldLinear) * dir : Vec3d(0.0); // per world unit
    double t0 = 0.0, t1 = length;
    if (grid.linear) {
        double b0, b1;
        if (!boxClip(pIndex, dIndex, boxMin, boxMax, b0, b1)) return 0.0;
        t0 = std::max(t0, b0);
        t1 = std::min(t1, b1);
    }
    const double h = step * grid.voxelLength;
    const double n = std::ceil((t1 - t0) / h);
    if (!(n > 0.0)) return 0.0;
    const double dt = (t1 - t0) / n; // equal parts, midpoints: the segment's integral
    double depth = 0.0;
    for (double k = 0.0; k < n; k += 1.0) {
        const double t = t0 + (k + 0.5) * dt;
        const Vec3d q = grid.linear ? pIndex + t * dIndex : grid.worldToIndex(pWorld + t * dir);
        float d = 0.0f;
        openvdb::tools::BoxSampler::sample(accessor, openvdb::Vec3d(q.x, q.y, q.z), d);
        if (d >= cutoff) depth += double(d);
    }
    return depth * dt / grid.voxelLength;
}

Vec3d PointLightMap::rayDirection(const Face& f, int i, int j) const
{
    // Equi-angular: the face's coordinates are angles, a = atan(tangent), so that the rays
    // spread evenly (a cube's corners hold 5.2 times the rays of its faces' centres otherwise).
    return glm::normalize(f.axis + std::tan(f.u0 + double(i) * mDu) * f.e1 + std::tan(f.v0 + double(j) * mDu) * f.e2);
}

PointLightMap::PointLightMap(const GridSource::Impl& grid, const RenderSettings& settings, const PointLight& light,
    double pointBudget, Progress* progress)
    : mLight(light.position), mStepVoxels(settings.shadow.step), mResolutionVoxels(settings.shadow.resolution)
{
    setUnits(progress, 6);
    const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
    if (box.empty()) return;
    const std::array<Vec3d, 8> corners = paddedBoxCorners(grid, box);
    Vec3d worldMin(std::numeric_limits<double>::max()), worldMax(-std::numeric_limits<double>::max());
    double farthest = 0.0;
    for (const Vec3d& c : corners) {
        worldMin = glm::min(worldMin, c);
        worldMax = glm::max(worldMax, c);
        farthest = std::max(farthest, glm::length(c - mLight));
    }
    const double ell = grid.voxelLength;
    // The faces: +x, -x, +y, -y, +z, -z, each with two axes across it.
    for (int f = 0; f < 6; ++f) {
        Vec3d axis(0.0), e1(0.0), e2(0.0);
        axis[f / 2] = f % 2 ? -1.0 : 1.0;
        e1[(f / 2 + 1) % 3] = 1.0;
        e2[(f / 2 + 2) % 3] = 1.0;
        mFaces[std::size_t(f)].axis = axis;
        mFaces[std::size_t(f)].e1 = e1;
        mFaces[std::size_t(f)].e2 = e2;
    }
    // Each face's window on the box: the projected corners' range, where every corner lies in
    // front of the face (a convex box projects inside its corners' hull); the whole face where
    // the box reaches behind the light's plane.
    std::array<std::array<double, 4>, 6> window; // u lo, u hi, v lo, v hi; empty if lo > hi
    for (std::size_t f = 0; f < 6; ++f) {
        const Face& face = mFaces[f];
        constexpr double kEdge = 0.78539816339744830962; // the face's edge: pi / 4
        double uLo = kEdge, uHi = -kEdge, vLo = kEdge, vHi = -kEdge, front = 0.0;
        bool straddles = false;
        for (const Vec3d& c : corners) {
            const Vec3d d = c - mLight;
            const double z = glm::dot(d, face.axis);
            front = std::max(front, z);
            if (!(z > 1e-9 * (glm::length(d) + ell))) {
                straddles = true;
                continue;
            }
            const double u = std::atan(glm::dot(d, face.e1) / z), v = std::atan(glm::dot(d, face.e2) / z);
            uLo = std::min(uLo, u), uHi = std::max(uHi, u), vLo = std::min(vLo, v), vHi = std::max(vHi, v);
        }
        if (!(front > 0.0)) {
            window[f] = {1.0, -1.0, 1.0, -1.0};
        } else if (straddles) {
            window[f] = {-kEdge, kEdge, -kEdge, kEdge};
        } else {
            window[f] = {std::max(uLo, -kEdge), std::min(uHi, kEdge), std::max(vLo, -kEdge), std::min(vHi, kEdge)};
        }
    }

    // The lattice: rays mResolutionVoxels apart where the box is farthest, samples every
    // mStepVoxels; both raised by one factor past the budget (points, and a sixteenth of it in
    // rays), as the directional light's map (docs/numerics.md#the-light-maps-budget).
    const double mostRays = pointBudget / 16.0;
    std::vector<std::int64_t> kLo;
    std::vector<std::int32_t> count;
    std::uint64_t total = 0;
    for (int attempt = 0;; ++attempt) {
        mStep = mStepVoxels * ell;
        mDu = mResolutionVoxels * ell / std::max(farthest, ell); // radians
        double rays = 0.0;
        for (std::size_t f = 0; f < 6; ++f) {
            Face& face = mFaces[f];
            const auto& w = window[f];
            face.nu = face.nv = 0;
            if (!(w[0] <= w[1] && w[2] <= w[3])) continue;
            // One ray more on each side: the bilinear lookup's neighbours at the window's edge.
            face.u0 = w[0] - mDu;
            face.v0 = w[2] - mDu;
            const double nu = std::ceil((w[1] - w[0]) / mDu) + 3.0, nv = std::ceil((w[3] - w[2]) / mDu) + 3.0;
            rays += nu * nv;
            if (rays > mostRays) break; // raised below before anything is allocated for them
            face.nu = int(nu);
            face.nv = int(nv);
        }
        // Samples along the rays: where each crosses the box's world bounds.
        double points = 0.0;
        if (rays <= mostRays) {
            kLo.clear();
            count.clear();
            for (std::size_t f = 0; f < 6; ++f) {
                Face& face = mFaces[f];
                face.firstRay = kLo.size();
                for (int j = 0; j < face.nv; ++j)
                    for (int i = 0; i < face.nu; ++i) {
                        double t0, t1;
                        std::int64_t lo = 0;
                        std::int32_t n = 0;
                        if (boxClip(mLight, rayDirection(face, i, j), worldMin, worldMax, t0, t1) && t1 > std::max(t0, 0.0)) {
                            lo = std::int64_t(std::min(std::floor(std::max(t0, 0.0) / mStep), 4e18));
                            n = std::int32_t(std::min(std::ceil(t1 / mStep) - double(lo) + 1.0, 2e9));
                        }
                        kLo.push_back(lo);
                        count.push_back(n);
                        points += double(n);
                    }
            }
        }
        const double scale = std::max(std::cbrt(points / pointBudget), std::sqrt(rays * 16.0 / pointBudget));
        if (!(scale > 1.0) || attempt == 8) {
            total = std::uint64_t(points);
            break;
        }
        mStepVoxels *= 1.01 * scale;
        mResolutionVoxels *= 1.01 * scale;
    }
    if (kLo.empty()) return;
    mRayKLo = std::move(kLo);
    mRayCount = std::move(count);
    mRayOffset.resize(mRayKLo.size());
    std::uint64_t offset = 0;
    for (std::size_t r = 0; r < mRayKLo.size(); ++r) {
        mRayOffset[r] = offset;
        offset += std::uint64_t(mRayCount[r]);
    }
    mDepth.assign(std::size_t(total), 0.0f);

    // March: D(k) = D(k - 1) + (d(k - 1) + d(k)) / 2 x step (the trapezoid rule from the light,
    // in voxel lengths); the first stored sample lies outside the padded box, where d = 0.
    const Mat3d toIndex = grid.linear ? glm::inverse(grid.indexToWorldLinear) : Mat3d(1.0);
    const Vec3d lightIndex = grid.worldToIndex(mLight);
    const float cutoff = float(settings.cutoff);
    for (std::size_t f = 0; f < 6; ++f) {
        const Face& face = mFaces[f];
        tbb::parallel_for(tbb::blocked_range<int>(0, face.nv), [&](const tbb::blocked_range<int>& range) {
            EmptySpaceSkipper skipper(*grid.field, 0);
            for (int j = range.begin(); j < range.end(); ++j) {
                if (progress) progress->check();
                for (int i = 0; i < face.nu; ++i) {
                    const std::size_t r = face.firstRay + std::size_t(j) * std::size_t(face.nu) + std::size_t(i);
                    const int n = mRayCount[r];
                    if (n == 0) continue;
                    const Vec3d dir = rayDirection(face, i, j), dirIndex = toIndex * dir;
                    float* out = mDepth.data() + mRayOffset[r];
                    double depth = 0.0, previous = 0.0;
                    for (int k = 0; k < n; ++k) {
                        const double t = double(mRayKLo[r] + k) * mStep;
                        const Vec3d p = grid.linear ? lightIndex + t * dirIndex : grid.worldToIndex(mLight + t * dir);
                        // Through an empty node: no density until the sample past its exit.
                        const double jump = grid.linear ? skipper.emptyExit(p, dirIndex) : 0.0;
                        if (jump > 0.0) {
                            const int last = std::min(n - 1, k + int(std::floor(jump / mStep)));
                            if (k > 0) depth += 0.5 * previous * mStepVoxels;
                            for (; k <= last; ++k) out[k] = float(depth);
                            --k;
                            previous = 0.0;
                            continue;
                        }
                        float v = 0.0f;
                        openvdb::tools::BoxSampler::sample(skipper.accessor(), openvdb::Vec3d(p.x, p.y, p.z), v);
                        const double d = v >= cutoff ? double(v) : 0.0;
                        if (k > 0) depth += 0.5 * (previous + d) * mStepVoxels;
                        out[k] = float(depth);
                        previous = d;
                    }
                }
            }
        });
        advance(progress);
    }
}

std::uint64_t PointLightMap::rays() const { return mRayKLo.size(); }

float PointLightMap::depthOnRay(std::size_t r, double w) const
{
    const int count = mRayCount[r];
    if (count == 0) return 0.0f;
    const double x = w - double(mRayKLo[r]);
    if (!(x > 0.0)) return 0.0f; // before the box: no density yet
    const float* d = mDepth.data() + mRayOffset[r];
    if (!(x < double(count - 1))) return d[count - 1]; // past the box: no density more
    const int k = int(x);
    return d[k] + float(x - double(k)) * (d[k + 1] - d[k]);
}

float PointLightMap::depth(const Vec3d& p) const
{
    if (mRayKLo.empty()) return 0.0f;
    const Vec3d d = p - mLight;
    const Vec3d a = glm::abs(d);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    if (!(a[axis] > 0.0)) return 0.0f; // at the light
    const Face& face = mFaces[std::size_t(2 * axis + (d[axis] < 0.0 ? 1 : 0))];
    if (face.nu == 0) return 0.0f;
    const double z = a[axis];
    const double fu = (std::atan(glm::dot(d, face.e1) / z) - face.u0) / mDu, fv = (std::atan(glm::dot(d, face.e2) / z) - face.v0) / mDu;
    const double iu = std::clamp(std::floor(fu), 0.0, double(face.nu - 2)), iv = std::clamp(std::floor(fv), 0.0, double(face.nv - 2));
    const float a0 = float(std::clamp(fu - iu, 0.0, 1.0)), b0 = float(std::clamp(fv - iv, 0.0, 1.0));
    const std::size_t r00 = face.firstRay + std::size_t(iv) * std::size_t(face.nu) + std::size_t(iu);
    const double w = glm::length(d) / mStep;
    const float d00 = depthOnRay(r00, w), d10 = depthOnRay(r00 + 1, w);
    const float d01 = depthOnRay(r00 + std::size_t(face.nu), w), d11 = depthOnRay(r00 + std::size_t(face.nu) + 1, w);
    return (1.0f - b0) * ((1.0f - a0) * d00 + a0 * d10) + b0 * ((1.0f - a0) * d01 + a0 * d11);
}

PointLights::PointLights(const GridSource::Impl& grid, const RenderSettings& settings, double pointBudget, Progress* progress)
    : mVoxelLength(grid.voxelLength)
{
    const OpticalModel model(settings);
    for (int c = 0; c < 3; ++c) mExtinction[c] = model.extinction(c);
    for (std::size_t l = 0; l < settings.pointLights.size(); ++l) {
        if (model.pointDark(l)) continue;
        mLights.push_back(settings.pointLights[l]);
        mScale.push_back({model.pointScale(l, 0), model.pointScale(l, 1), model.pointScale(l, 2)});
        mMaps.emplace_back(grid, settings, settings.pointLights[l], pointBudget, progress);
    }
}

std::array<double, 3> PointLights::transmittance(std::size_t l, const Vec3d& p) const
{
    const double depth = double(mMaps[l].depth(p));
    return {std::exp(-mExtinction[0] * depth), std::exp(-mExtinction[1] * depth), std::exp(-mExtinction[2] * depth)};
}

void PointLights::acrossLayer(std::size_t l, const Vec3d& w0, const Vec3d& w1, std::array<float, 3>& front, std::array<float, 3>& logRatio,
    float& falloff) const
{
    const double d0 = double(mMaps[l].depth(w0)), d1 = double(mMaps[l].depth(w1));
    for (std::size_t c = 0; c < 3; ++c) {
        const float log0 = float(-mExtinction[c] * d0), log1 = float(-mExtinction[c] * d1);
        front[c] = std::exp(log0);
        logRatio[c] = lightLogRatio(log0, log1);
    }
    falloff = float(pointLightFalloff(mLights[l], 0.5 * (w0 + w1), mVoxelLength));
}

} // namespace detail
} // namespace vdb_ewa
