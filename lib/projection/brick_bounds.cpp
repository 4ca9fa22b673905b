/// @file brick_bounds.cpp
#include "projection/brick_bounds.h"

#include "projection/splat_projection.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

/// The largest eigenvalue of the symmetric positive definite @a m (power iteration from a
/// vector no eigenvector is orthogonal to in practice), with a relative slack of 1e-6 above.
double largestEigenvalue(const Mat3d& m)
{
    Vec3d v(0.577, 0.5774, 0.5773);
    double lambda = 0.0;
    for (int i = 0; i < 200; ++i) {
        const Vec3d w = m * v;
        const double n = glm::length(w);
        if (!(n > 0.0)) return 0.0;
        lambda = n / glm::length(v);
        v = w / n;
    }
    return lambda * (1.0 + 1e-6);
}

} // namespace

BrickBounder::BrickBounder(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings, const LevelOfDetail* lod,
    const SlabGrid& slabs)
    : mGrid(grid), mCamera(camera), mSettings(settings), mLod(lod), mSlabs(slabs)
{
    // Splats end at the cut-off ellipse (cutoffRadius sigmas) across the ray and at
    // kDepthTruncation sigmas along it (splat_projection.cpp).
    mReachSigmas = std::max(settings.splat.cutoffRadius, kDepthTruncation);
    // A kernel is a sphere of sigma x reach in index space; A maps it into the ellipsoid whose
    // extent along any direction is at most kappa(A) times the sphere's image radius there.
    const Mat3d ata = glm::transpose(grid.indexToWorldLinear) * grid.indexToWorldLinear;
    const double most = largestEigenvalue(ata), least = 1.0 / largestEigenvalue(glm::inverse(ata));
    mStretch = std::sqrt(most / least);
    // Motion blur: a sub-kernel's centre lies within the largest travel of its still centre, and
    // its path (at most twice that) adds |path| / sqrt(12) to its standard deviation along it
    // (kernel_motion.h); |A^-1| = 1 / sqrt(least) takes world lengths to index lengths.
    const double travel = largestTravel(grid, settings);
    mMotionPad = travel * (1.0 + 2.0 * mReachSigmas / std::sqrt(12.0)) / std::sqrt(least);
    // Every anti-aliasing rule but Swan's adds at most the low-pass variance to each axis.
    mFilterPixels = settings.splat.cutoffRadius * std::sqrt(settings.splat.lowpass) + 1.0;
    mMaxTan[0] = 1.3 * 0.5 * camera.width() / camera.focalPixels();
    mMaxTan[1] = 1.3 * 0.5 * camera.height() / camera.focalPixels();
}

BrickBounds BrickBounder::bound(const Brick& brick) const
{
    BrickBounds b;
    // The widest kernel the brick can make: level-of-detail blocks (8 voxels), an active
    // tile's lattice, or voxels; voxels' halo kernels (--prefilter) sit one voxel outside.
    int spacing = 1;
    if (!brick.leaf) {
        spacing = tileLattice(brick.box, mSettings.splat.tileKernelSpacing, mLod).widest();
    } else if (mLod) {
        // A block's continuous level is at most the node's size level; it splits between that
        // level's floor and the next (LevelOfDetail::blockLevels, split).
        const LevelOfDetail::NodeLevels node = mLod->nodeLevels(brick.box.min(), brick.box.dim().x());
        if (node.merges()) spacing = 1 << std::min(LevelOfDetail::kMaxLevel, int(std::floor(node.size)) + 1);
    }
    const auto sigma = [&](int s) { return kernelSigmaVoxels(Kernel{Vec3d(0.0), 0.0f, float(s)}, mSettings.splat.kernelSigma); };
    // Voxel kernels lie at the active voxels; merged blocks' centres anywhere in the node.
    openvdb::CoordBBox box = brick.box;
    if (brick.leaf && spacing == 1) {
        box = openvdb::CoordBBox();
        brick.leaf->evalActiveBoundingBox(box, true);
        if (box.empty()) box = brick.box;
    }
    const double pad = mStretch * mReachSigmas * std::max(sigma(spacing), sigma(1)) + 1.0 + mMotionPad;
    const Vec3d lo = Vec3d(box.min().x(), box.min().y(), box.min().z()) - pad;
    const Vec3d hi = Vec3d(box.max().x(), box.max().y(), box.max().z()) + pad;

    // The padded box's corners in camera space; its world AABB for the nearest distance.
    const bool perspective = mCamera.projection() == Projection::Perspective;
    Vec3d t[8], worldLo(std::numeric_limits<double>::infinity()), worldHi(-std::numeric_limits<double>::infinity());
    double zMin = std::numeric_limits<double>::infinity(), zMax = -zMin;
    for (int i = 0; i < 8; ++i) {
        const Vec3d p((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
        const Vec3d w = mGrid.indexToWorld(p);
        worldLo = glm::min(worldLo, w);
        worldHi = glm::max(worldHi, w);
        t[i] = mCamera.cameraFromWorldPoint(w);
        zMin = std::min(zMin, t[i].z);
        zMax = std::max(zMax, t[i].z);
    }
    if (perspective) {
        const Vec3d gap = glm::max(glm::max(worldLo - mCamera.eye(), mCamera.eye() - worldHi), Vec3d(0.0));
        b.nearestSlab = mSlabs.index(glm::length(gap)) - 1;
    } else {
        b.nearestSlab = mSlabs.index(zMin) - 1;
    }
    if (!(zMax > mCamera.near()) || zMin > mCamera.far()) {
        b.visible = false; // every kernel before the near plane or beyond the far one
        return b;
    }
    // The whole image where a kernel may reach the near plane or the eye (then the
    // projection forms J elsewhere than at the centre, or the box's image is unbounded).
    const auto wholeImage = [&] {
        b.x0 = b.y0 = 0;
        b.x1 = mCamera.width() - 1;
        b.y1 = mCamera.height() - 1;
        return b;
    };
    const double f = mCamera.focalPixels();
    const Vec2d c = mCamera.principalPoint();
    const double worldSigma = mStretch * sigma(spacing) * glm::length(mGrid.indexToWorldLinear * Vec3d(1.0, 0.0, 0.0));
    if (perspective && !(zMin > mCamera.near())) return wholeImage();
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0, tanMax = 0.0;
    bool grazing = false;
    for (const Vec3d& p : t) {
        const Vec2d r = perspective ? Vec2d(p.x / p.z, p.y / p.z) : Vec2d(p.x, p.y);
        grazing = grazing || (perspective && (std::abs(r.x) > mMaxTan[0] || std::abs(r.y) > mMaxTan[1]));
        tanMax = std::max({tanMax, std::abs(r.x), std::abs(r.y)});
        x0 = std::min(x0, c.x + f * r.x);
        x1 = std::max(x1, c.x + f * r.x);
        y0 = std::min(y0, c.y + f * r.y);
        y1 = std::max(y1, c.y + f * r.y);
    }
    double margin = mFilterPixels;
    if (perspective && mCamera.lensRadius() > 0.0) {
        // Depth of field: the circle of confusion's covariance (R/2)^2 I widens the cut-off
        // ellipse by at most the cut-off times R/2, R largest at the box's nearest or farthest depth.
        const double r = std::max(mCamera.confusionRadius(zMin), mCamera.confusionRadius(zMax));
        margin += mSettings.splat.cutoffRadius * 0.5 * r;
    }
    if (perspective) {
        // A splat is the local affine map of its kernel (Eq. 30): it leaves the box's
        // perspective image by at most the second-order term, f |d|^2 / z^2 (1 + 2 |tan|) / 2,
        // |d| the box's diagonal, z its nearest depth. Near the eye the projection's own clamp
        // applies (J formed 3 sizes away, ewa_kernel.cpp): the whole image.
        const double diagonal = glm::length(worldHi - worldLo), ratio = diagonal / zMin;
        if (ratio > 0.5 || zMin < 4.0 * std::sqrt(3.0) * worldSigma) return wholeImage();
        margin += f * ratio * ratio * (1.0 + tanMax) * 2.0;
        // A kernel whose centre lies beyond 1.3x the frustum's edge has J formed at the edge:
        // its footprint, around its own centre (inside the box's image), reaches at most the
        // cut-off times its width there, f sigma sqrt(1 + tan^2) / z for the widest tan.
        if (grazing) {
            const double tanEdge = std::max(mMaxTan[0], mMaxTan[1]);
            margin = std::max(margin, mFilterPixels + mReachSigmas * f * worldSigma * (1.0 + tanEdge * tanEdge) / zMin);
        }
    }
    const double px0 = std::floor(x0 - margin - 0.5), px1 = std::ceil(x1 + margin - 0.5);
    const double py0 = std::floor(y0 - margin - 0.5), py1 = std::ceil(y1 + margin - 0.5);
    if (px1 < 0.0 || py1 < 0.0 || px0 > mCamera.width() - 1 || py0 > mCamera.height() - 1) {
        b.visible = false;
        return b;
    }
    b.x0 = int(std::max(px0, 0.0));
    b.y0 = int(std::max(py0, 0.0));
    b.x1 = int(std::min(px1, double(mCamera.width() - 1)));
    b.y1 = int(std::min(py1, double(mCamera.height() - 1)));
    return b;
}

} // namespace detail
} // namespace vdb_ewa
