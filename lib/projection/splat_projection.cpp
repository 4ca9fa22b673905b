/// @file splat_projection.cpp
#include "projection/splat_projection.h"

#include "shading/shading.h"
#include "source/source.h"
#include "support/matrix_norm.h"

#include <vdb_ewa/ewa_kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdb_ewa {
namespace detail {
namespace {

/// --precision float: the world -> camera transform in single precision, as a float
/// pipeline would do it (world positions and the eye rounded to float before subtracting).
Vec3d cameraFromWorldFloat(const Camera& camera, const Vec3d& pWorld)
{
    const glm::vec3 d = glm::vec3(pWorld) - glm::vec3(camera.eye());
    return Vec3d(glm::mat3(camera.cameraFromWorld()) * d);
}

/// Where a kernel lies along its viewing ray; slabShares() turns it into shares twice
/// (once to count, once to fill), with identical results.
struct DepthExtent
{
    double mu, sd, clipNear, clipFar;
};

} // namespace

ProjectionParams projectionParams(const Camera& camera, const SplatOptions& splat)
{
    ProjectionParams p;
    p.perspective = camera.projection() == Projection::Perspective;
    p.focalPixels = camera.focalPixels();
    p.principalPoint = camera.principalPoint();
    p.maxTanX = 1.3 * 0.5 * camera.width() / camera.focalPixels();
    p.maxTanY = 1.3 * 0.5 * camera.height() / camera.focalPixels();
    p.antiAliasing = splat.antiAliasing;
    p.lowpass = splat.lowpass;
    p.cutoffRadius = splat.cutoffRadius;
    p.renormalize = splat.renormalize;
    p.taper = splat.taper;
    const Mat2d& lens = camera.lensCovariance();
    p.lens = Sym2{lens[0][0], lens[1][0], lens[1][1]};
    p.focusDepth = camera.focusDepth();
    return p;
}

bool pixelBox(const Footprint& fp, int width, int height, int& x0, int& y0, int& x1, int& y1)
{
    // Pixels whose centre (i + 0.5) lies within the cut-off box.
    const double bx0 = std::ceil(fp.centre.x - fp.halfExtent.x - 0.5);
    const double bx1 = std::floor(fp.centre.x + fp.halfExtent.x - 0.5);
    const double by0 = std::ceil(fp.centre.y - fp.halfExtent.y - 0.5);
    const double by1 = std::floor(fp.centre.y + fp.halfExtent.y - 0.5);
    if (bx1 < 0.0 || by1 < 0.0 || bx0 > width - 1 || by0 > height - 1 || bx0 > bx1 || by0 > by1) return false;
    x0 = int(std::max(bx0, 0.0));
    x1 = int(std::min(bx1, double(width - 1)));
    y0 = int(std::max(by0, 0.0));
    y1 = int(std::min(by1, double(height - 1)));
    return true;
}

namespace {

/// A slab is no thinner than LevelOfDetail::latticePixels / kSlabsPerLodPixel pixel widths at
/// the nearest active value: depth resolved finer than a fraction of what the pixels resolve
/// across costs a share in every slab a kernel spans and changes nothing one can see (eight root
/// tiles of 4096^3 voxels under a fifth of a pixel each: tile kernels 110 slabs deep, 26.5 s at
/// 160x90; docs/numerics.md#dense-faces).
constexpr double kSlabsPerLodPixel = 16.0;

} // namespace

SlabGrid frameSlabs(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings)
{
    SlabGrid slabs;
    const bool perspective = camera.projection() == Projection::Perspective;
    slabs.zBase = perspective ? 0.0 : camera.near();
    slabs.thickness = settings.splat.slab * grid.voxelLength;
    if (!grid.linear) return slabs;
    const openvdb::CoordBBox box = grid.grid->evalActiveVoxelBoundingBox(); // a walk of the tree: only where used
    if (box.empty()) return slabs;
    // A pixel's width at the nearest active value: from the eye to the world box around the
    // active voxels' box (padded half a voxel), which lies no farther (orthographic: the same
    // everywhere).
    double nearest = 1.0;
    if (perspective) {
        Vec3d lo(1e300), hi(-1e300);
        for (int c = 0; c < 8; ++c) {
            const Vec3d p(c & 1 ? box.max().x() + 0.5 : box.min().x() - 0.5, c & 2 ? box.max().y() + 0.5 : box.min().y() - 0.5,
                c & 4 ? box.max().z() + 0.5 : box.min().z() - 0.5);
            const Vec3d w = grid.indexToWorld(p);
            lo = glm::min(lo, w);
            hi = glm::max(hi, w);
        }
        nearest = glm::length(camera.eye() - glm::clamp(camera.eye(), lo, hi));
    }
    slabs.thickness = std::max(slabs.thickness, LevelOfDetail::latticePixels(settings.splat) / kSlabsPerLodPixel * nearest / camera.focalPixels());
    return slabs;
}

double slabsSpanned(const GridSource::Impl& grid, const SlabGrid& slabs, const RenderSettings& settings, double spacing)
{
    // kDepthTruncation sigmas either side of the centre along the ray, sigma =
    // kernelSigmaVoxels(spacing) index lengths, stretched by at most the Frobenius norm of A.
    const double sd = frobeniusNorm(grid.indexToWorldLinear) * kernelSigmaVoxels(Kernel{Vec3d(0.0), 0.0f, float(spacing)}, settings.splat.kernelSigma);
    return 2.0 * kDepthTruncation * sd / slabs.thickness;
}

double widestLatticeSpacing(const GridSource::Impl& grid, const SlabGrid& slabs, const RenderSettings& settings)
{
    if (!grid.linear) return std::numeric_limits<double>::infinity();
    // Coarse kernels' reach is proportional to their spacing (kCoarseKernelSigma x spacing or
    // more): spacing 2 spans slabsSpanned(2) slabs.
    return 2.0 * double(kSlabSpanTarget) / slabsSpanned(grid, slabs, settings, 2.0);
}

SplatSet projectSplats(const GridSource::Impl& grid, const KernelSet& kernels, const std::vector<Rgb>& colors,
    const Camera& camera, const RenderSettings& settings, const PassRequest& passes, Progress* progress, const SlabGrid* slabs)
{
    SplatSet out;
    const ProjectionParams params = projectionParams(camera, settings.splat);
    const bool perspective = params.perspective;
    const Mat3d R = camera.cameraFromWorld();
    const double ell = grid.voxelLength;
    out.slabs = slabs ? *slabs : frameSlabs(grid, camera, settings);

    // Affine grids: camera-space covariance of a unit kernel, formed once per frame (Eq. 31).
    const Mat3d RA = R * grid.indexToWorldLinear;
    const Mat3d covUnit = RA * glm::transpose(RA);
    const double volumeUnit = std::abs(glm::determinant(grid.indexToWorldLinear));

    const OpticalModel model(settings);
    const int width = camera.width(), height = camera.height();
    const auto& xform = grid.grid->transform();

    const std::size_t n = kernels.kernels.size();
    const PassLayout layout(passes);
    const int passCount = layout.count;
    LargeArray<float> passSources(n * std::size_t(passCount) * 3);
    LargeArray<std::uint8_t> visible(n, 0);
    LargeArray<Splat> splats(n);
    LargeArray<DepthExtent> extents(n);
    LargeArray<std::uint8_t> flags(n, 0); // 1: before near, 2: clamped near, 4: clamped grazing

    // Pass 1: footprints, culling and depth extents.
    setUnits(progress, n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
        [&](const tbb::blocked_range<std::size_t>& range) {
            ProjectionParams refinedParams = params;
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const Kernel& k = kernels.kernels[i];
                Vec3d pWorld = grid.indexToWorld(k.pIndex);
                Mat3d cov;
                double volume;
                if (grid.linear) {
                    cov = covUnit;
                    volume = volumeUnit;
                } else {
                    const Mat3d a = R * indexToWorldJacobian(xform, openvdb::Vec3d(k.pIndex.x, k.pIndex.y, k.pIndex.z));
                    cov = a * glm::transpose(a);
                    volume = std::abs(glm::determinant(a));
                }
                const double s = k.spacing, sigma = kernelSigmaVoxels(k, settings.splat.kernelSigma);
                cov *= sigma * sigma;
                if (!kernels.motion.empty()) {
                    // Motion blur: the kernel at the shutter's mid-time, convolved with a box
                    // along its path, whose covariance is path path^T / 12 (kernel_motion.h).
                    const KernelMotion& m = kernels.motion[i];
                    pWorld += Vec3d(m.shift[0], m.shift[1], m.shift[2]);
                    const Vec3d path = R * Vec3d(m.path[0], m.path[1], m.path[2]);
                    cov += glm::outerProduct(path, path) / 12.0;
                }
                const Vec3d t = settings.splat.doublePrecision ? camera.cameraFromWorldPoint(pWorld)
                                                               : cameraFromWorldFloat(camera, pWorld);
                if (!settings.splat.doublePrecision) cov = Mat3d(glm::mat3(cov));
                if (perspective && !(t.z > camera.near())) { // centre before the near plane
                    flags[i] = 1;
                    continue;
                }
                // Refined kernels (spacing s = 1/n, only where voxels span n pixels or more) take
                // the low-pass floor scaled with their lattice, lowpass s^2: their sum is as
                // smooth on the pixel grid as the voxels' (docs/numerics.md#refined-kernels).
                // The lattice's own spacing, not --refine: the budget may have lowered n.
                refinedParams.lowpass = params.lowpass * s * s;
                const Footprint fp = projectKernel(t, cov, s < 1.0 ? refinedParams : params);
                if (!fp.valid) continue;
                flags[i] = std::uint8_t((fp.clampedNear ? 2 : 0) | (fp.clampedGrazing ? 4 : 0));

                Splat& sp = splats[i];
                if (!pixelBox(fp, width, height, sp.x0, sp.y0, sp.x1, sp.y1)) continue;

                // Near/far planes clip the kernel's depth integral (perspective: the plane depth
                // converted to distance along the ray through the centre).
                const double toRay = perspective ? glm::length(t) / t.z : 1.0;
                const DepthExtent extent{fp.depth, fp.depthSd, camera.near() * toRay, camera.far() * toRay};
                double lo, hi;
                if (!clippedDepthRange(extent.mu, extent.sd, kDepthTruncation, extent.clipNear, extent.clipFar, lo, hi)) {
                    continue; // wholly before the near plane or beyond the far plane
                }
                extents[i] = extent;

                setFootprint(sp, fp, params.cutoffRadius);
                sp.layerFirst = kernels.motion.empty() ? 0 : kernels.motion[i].layerFirst;
                sp.layerCount = kernels.motion.empty() ? 0 : kernels.motion[i].layerCount;
                // Weight w_k = density x voxel volume / voxel length (Eq. 8 with extinction
                // per voxel length), times the footprint peak (Eq. 32, 33): the peak optical
                // depth in voxel lengths of unit density.
                const double weight = double(k.density) * volume * s * s * s / ell * fp.peak;
                // Source terms: the self-emission and the ambient light scattered (optical
                // depth x their radiance per unit optical depth, never shadowed) and the
                // scattering weight, lit by the compositor per slab sample.
                float* pass = passSources.data() + i * std::size_t(passCount) * 3;
                if (i >= kernels.emitterBegin) {
                    // An emitter: its radiance per voxel length x its weight in voxel lengths,
                    // no optical depth (docs/equations.md#emission-grids).
                    const std::array<float, 3>& radiance = kernels.emitted[i - kernels.emitterBegin];
                    for (int c = 0; c < 3; ++c) {
                        sp.tau[c] = sp.scatter[c] = 0.0f;
                        sp.emission[c] = float(weight * double(radiance[std::size_t(c)]));
                        if (layout.shadow >= 0) pass[3 * layout.shadow + c] = 0.0f;
                        if (layout.emission >= 0) pass[3 * layout.emission + c] = sp.emission[c];
                    }
                    visible[i] = 1;
                    continue;
                }
                for (int c = 0; c < 3; ++c) {
                    const double tau = model.opticalDepth(c, weight, 1.0);
                    sp.tau[c] = float(tau);
                    const double color = colors.empty() ? 1.0 : double(colors[i][c]);
                    sp.emission[c] = float(tau * (model.emitted(c) + model.ambient(c, color)));
                    sp.scatter[c] = float(tau * color);
                    if (layout.shadow >= 0) pass[3 * layout.shadow + c] = 0.0f; // lit per slab sample
                    if (layout.emission >= 0) pass[3 * layout.emission + c] = float(tau * model.emitted(c));
                }
                visible[i] = 1;
            }
            advance(progress, range.size());
        });

    // Slab thickness: --slab voxel lengths, raised where a kernel is so long along the ray
    // (1000:1 voxels, frustum maps) that it would span more than kSlabSpanTarget slabs.
    double maxSd = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        if (visible[i]) maxSd = std::max(maxSd, extents[i].sd);
    }
    const double minThickness = 2.0 * kDepthTruncation * maxSd / double(kSlabSpanTarget);
    if (!slabs && minThickness > out.slabs.thickness) {
        out.requestedThickness = out.slabs.thickness;
        out.slabs.thickness = minThickness;
    }

    // Pass 2: slab spans, compaction in kernel order, and the layout of the shares.
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < n; ++i) {
        out.beforeNear += (flags[i] & 1);
        if (!visible[i]) continue;
        const DepthExtent& e = extents[i];
        const std::int64_t span = slabSpan(out.slabs, e.mu, e.sd, kDepthTruncation, e.clipNear, e.clipFar, splats[i].firstSlab);
        out.clippedSpan += (span > kMaxSlabSpan);
        out.clampedNear += (flags[i] >> 1) & 1;
        out.clampedGrazing += (flags[i] >> 2) & 1;
        splats[i].shareOffset = total;
        splats[i].slabCount = std::uint32_t(std::min<std::int64_t>(span, kMaxSlabSpan));
        total += splats[i].slabCount;
    }
    out.shares.resize(total);
    out.shareMoments.resize(2 * total);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
        [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                if (!visible[i]) continue;
                const DepthExtent& e = extents[i];
                std::int64_t first = 0;
                slabShares(out.slabs, e.mu, e.sd, kDepthTruncation, e.clipNear, e.clipFar, first,
                    out.shares.data() + splats[i].shareOffset, int(splats[i].slabCount),
                    out.shareMoments.data() + 2 * splats[i].shareOffset);
            }
        });
    // Compacted in place, in kernel order (no second array of splats to touch).
    const std::size_t passFloats = std::size_t(passCount) * 3;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!visible[i]) continue;
        splats[kept] = splats[i];
        std::copy_n(passSources.data() + i * passFloats, passFloats, passSources.data() + kept * passFloats);
        ++kept;
    }
    if (!kernels.motion.empty() && settings.motionBlur.lightFollows) {
        out.shifts.resize(3 * kept);
        for (std::size_t i = 0, at = 0; i < n; ++i) {
            if (visible[i]) std::copy_n(kernels.motion[i].shift, 3, out.shifts.data() + 3 * at++);
        }
    }
    splats.resize(kept);
    passSources.resize(kept * passFloats);
    out.splats = std::move(splats);
    out.passSourceCount = passCount;
    out.passSources = std::move(passSources);
    out.culled = n - kept;
    return out;
}

} // namespace detail
} // namespace vdb_ewa
