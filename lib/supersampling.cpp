/// @file supersampling.cpp
#include "supersampling.h"

#include "source/source.h"
#include "support/blank_frame.h"
#include "support/matrix_norm.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Index-space padding of the active box that every kernel's reach fits in: 3 standard
/// deviations of a level-of-detail block of 8 voxels (sigma 4, centred 4 inside) or a draft
/// tile lattice (spacing 8, sigma 4.8), a halo voxel (--prefilter), rounded up; larger tiles'
/// lattices (up to one kernel the tile's size, seen small) add the reach of the largest tile's.
constexpr double kKernelReachVoxels = 16.0;

/// Sub-pixels multiply the kernels of active tiles larger than a leaf node by up to S^3 (their
/// lattices follow the sub-pixels, docs/equations.md#active-tiles-seen-small): S is lowered
/// until they are at most this many a pixel of the image, between kTileKernelsAtLeast and
/// kTileKernelsAtMost (so that a thumbnail costs what a thumbnail resolves).
constexpr double kTileKernelsAPixel = 32.0;
constexpr double kTileKernelsAtLeast = double(1 << 16);
constexpr double kTileKernelsAtMost = double(1 << 21);

/// Calls @a f(box) for each active tile of @a grid.
template <typename F>
void forEachActiveTile(const openvdb::FloatGrid& grid, F&& f)
{
    auto it = grid.tree().cbeginValueOn();
    it.setMaxDepth(openvdb::FloatTree::ValueOnCIter::LEAF_DEPTH - 1); // tiles only, no voxel
    for (; it; ++it) {
        openvdb::CoordBBox box;
        it.getBoundingBox(box);
        f(box);
    }
}

/// The largest active tile's edge, in voxels (0: none).
int largestActiveTile(const openvdb::FloatGrid& grid)
{
    int largest = 0;
    forEachActiveTile(grid, [&](const openvdb::CoordBBox& box) { largest = std::max(largest, box.dim().x()); });
    return largest;
}

/// The kernels the active tiles larger than a leaf node make through @a camera (tileLattice,
/// without the slabs' limit), counted up to @a most.
double tileKernels(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings, double most)
{
    const LevelOfDetail lod(grid, camera, settings);
    double kernels = 0.0;
    forEachActiveTile(*grid.field, [&](const openvdb::CoordBBox& box) {
        if (kernels > most || box.dim().x() <= int(openvdb::FloatTree::LeafNodeType::DIM)) return;
        kernels += double(tileLattice(box, settings.splat.tileKernelSpacing, &lod).kernels(box.dim().x()));
    });
    return kernels;
}

} // namespace

double supersampledPixelBudget(int width, int height)
{
    return std::max(16.0 * double(width) * double(height), double(1 << 22));
}

double tileKernelBudget(int width, int height)
{
    return std::clamp(kTileKernelsAPixel * double(width) * double(height), kTileKernelsAtLeast, kTileKernelsAtMost);
}

namespace {

/// The @a quantile of @a sizes (pixels, active voxels), weighted by their voxels; +inf for none.
double weightedQuantile(std::vector<std::pair<double, double>>& sizes, double quantile)
{
    if (sizes.empty()) return kInf;
    std::sort(sizes.begin(), sizes.end());
    double total = 0.0;
    for (const auto& s : sizes) total += s.second;
    double below = 0.0;
    for (const auto& s : sizes) {
        below += s.second;
        if (below >= quantile * total) return std::isnan(s.first) ? kInf : s.first;
    }
    return sizes.back().first;
}

/// (its screen size as @a size(box) gives it, active voxels) of each leaf node and each active
/// tile of @a grid (a tile counts as its voxels); a leaf's box is its node's, or with
/// @a activeBox the box of its active voxels.
template <typename Size>
std::vector<std::pair<double, double>> nodeSizes(const GridSource::Impl& grid, bool activeBox, const Size& size)
{
    std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
    grid.field->tree().getNodes(leaves);
    std::vector<std::pair<double, double>> sizes(leaves.size()); // (pixels, active voxels)
    tbb::parallel_for(std::size_t(0), leaves.size(), [&](std::size_t i) {
        openvdb::CoordBBox box = leaves[i]->getNodeBoundingBox();
        if (activeBox) {
            box = openvdb::CoordBBox();
            leaves[i]->evalActiveBoundingBox(box, false);
        }
        sizes[i] = {box.empty() ? std::numeric_limits<double>::quiet_NaN() : size(box), double(leaves[i]->onVoxelCount())};
    });
    forEachActiveTile(*grid.field, [&](const openvdb::CoordBBox& box) {
        const double dim = double(box.dim().x());
        sizes.emplace_back(size(box), dim * dim * dim);
    });
    return sizes;
}

} // namespace

double medianVoxelPixels(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings)
{
    const LevelOfDetail lod(grid, camera, settings);
    // Active tiles count as their voxels: a dense tile's face is as sharp as a voxel's, and
    // seen small it covers too much at one sample a pixel as voxels do (a cube of 2^3 tiles of
    // 128^3 voxels 5 pixels wide: alpha +168 %, +22 % at 8 x 8 sub-pixels). What their kernels
    // cost with sub-pixels is bounded in chooseSupersampling (tileKernelBudget).
    auto sizes = nodeSizes(grid, false, [&](const openvdb::CoordBBox& box) { return lod.voxelPixels(box.min(), box.dim().x()); });
    return weightedQuantile(sizes, 0.5);
}

double voxelPixelsInView(const GridSource::Impl& grid, const Camera& camera, double quantile)
{
    if (!grid.grid || !grid.field) return kInf;
    const auto& xform = grid.grid->transform();
    const bool perspective = camera.projection() == Projection::Perspective;
    auto sizes = nodeSizes(grid, true, [&](const openvdb::CoordBBox& box) {
        const openvdb::Vec3d cIndex = 0.5 * (box.min().asVec3d() + box.max().asVec3d());
        const double side = double(std::max({box.dim().x(), box.dim().y(), box.dim().z()})); // voxels
        const double axis = longestIndexAxis(xform, cIndex);
        const openvdb::Vec3d w = xform.indexToWorld(cIndex);
        const Vec3d c = camera.cameraFromWorldPoint(Vec3d(w.x(), w.y(), w.z()));
        if (perspective && !(c.z > camera.near())) return std::numeric_limits<double>::quiet_NaN(); // behind the near plane
        const double scale = perspective ? camera.focalPixels() / c.z : camera.focalPixels();
        // Out of the frame: the node's bounding sphere misses it.
        const Vec2d p = camera.rasterFromCamera(c);
        const double reach = 0.5 * std::sqrt(3.0) * side * axis * scale;
        if (p.x + reach < 0.0 || p.y + reach < 0.0 || p.x - reach > camera.width() || p.y - reach > camera.height()) {
            return std::numeric_limits<double>::quiet_NaN();
        }
        return axis * scale;
    });
    sizes.erase(std::remove_if(sizes.begin(), sizes.end(), [](const auto& s) { return std::isnan(s.first); }), sizes.end());
    double pixels = weightedQuantile(sizes, quantile);
    // Emission and temperature grids' voxels are detail of the image too: the finer measure.
    for (const auto* emitter : {grid.emission.get(), grid.temperature.get()}) {
        if (emitter) pixels = std::min(pixels, voxelPixelsInView(*emitter, camera, quantile));
    }
    return pixels;
}

Supersampling reachedWindow(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings)
{
    Supersampling whole;
    whole.width = camera.width();
    whole.height = camera.height();
    if (!grid.linear) return whole;
    openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
    for (const auto* emitter : {grid.emission.get(), grid.temperature.get()}) {
        if (emitter) box.expand(emitter->field->evalActiveVoxelBoundingBox());
    }
    Supersampling none;
    if (box.empty()) return none;
    // Motion blur's largest travel in index units (|A^-1| <= its Frobenius norm).
    const double travel = largestTravel(grid, settings) * frobeniusNorm(glm::inverse(grid.indexToWorldLinear));
    const int largest = largestActiveTile(*grid.field);
    const double tileReach = largest > 0 ? settings.splat.cutoffRadius * kernelSigmaVoxels(Kernel{Vec3d(0.0), 0.0f, float(largest)}, settings.splat.kernelSigma) : 0.0;
    const double pad = std::max(kKernelReachVoxels, tileReach) + travel;
    const Vec3d lo = Vec3d(box.min().x(), box.min().y(), box.min().z()) - pad;
    const Vec3d hi = Vec3d(box.max().x(), box.max().y(), box.max().z()) + pad;
    // The box's image is the hull of its corners' where every corner is in front of the near
    // plane (a perspective projection keeps lines straight there).
    double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf, lens = 0.0;
    for (int c = 0; c < 8; ++c) {
        const Vec3d index((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
        const Vec3d t = camera.cameraFromWorldPoint(grid.indexToWorld(index));
        if (camera.projection() == Projection::Perspective && !(t.z > camera.near())) return whole;
        const Vec2d p = camera.rasterFromCamera(t);
        if (!std::isfinite(p.x) || !std::isfinite(p.y)) return whole;
        x0 = std::min(x0, p.x);
        x1 = std::max(x1, p.x);
        y0 = std::min(y0, p.y);
        y1 = std::max(y1, p.y);
        lens = std::max(lens, camera.confusionRadius(t.z));
    }
    // The low-pass filter's reach (at most the pixel's; a sub-pixel's is smaller), the lens's
    // circle of confusion at the box's nearest and farthest corners (the radius is monotonic
    // on either side of the focus), and two pixels for rounding and Eq. 30's affine error.
    const double margin = settings.splat.cutoffRadius * std::sqrt(std::max(settings.splat.lowpass, 1.0)) + lens + 2.0;
    const double W = camera.width(), H = camera.height();
    const double fx0 = std::clamp(std::floor(x0 - margin), 0.0, W), fx1 = std::clamp(std::ceil(x1 + margin), 0.0, W);
    const double fy0 = std::clamp(std::floor(y0 - margin), 0.0, H), fy1 = std::clamp(std::ceil(y1 + margin), 0.0, H);
    if (!(fx1 > fx0 && fy1 > fy0)) return none;
    Supersampling window;
    window.x0 = int(fx0);
    window.y0 = int(fy0);
    window.width = int(fx1) - window.x0;
    window.height = int(fy1) - window.y0;
    return window;
}

Supersampling chooseSupersampling(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, const MemoryBudget& budget, std::vector<std::string>& warnings)
{
    Supersampling one;
    one.width = camera.width();
    one.height = camera.height();
    if (settings.splat.supersample <= 1) return one;
    const double px = medianVoxelPixels(grid, camera, settings);
    one.voxelPixels = px;
    if (!(px > 0.0) || px >= settings.splat.supersampleSpan) return one; // also +inf
    const int wanted = int(std::min(double(settings.splat.supersample), std::ceil(settings.splat.supersampleSpan / px)));
    if (wanted <= 1) return one;
    if (passes.deep) {
        std::ostringstream w;
        w << "--deep: composited at one sample a pixel, not the " << wanted << "x" << wanted
          << " sub-pixels the voxels ask for (--supersample: a deep image has no average of sub-pixels); the volume's voxels span "
          << px << " pixels, so its edges and fine detail render more opaque than a camera's average";
        warnings.push_back(w.str());
        return one;
    }
    Supersampling s = reachedWindow(grid, camera, settings);
    s.voxelPixels = px;
    if (s.width == 0) return one; // nothing in view
    const double pixels = double(s.width) * double(s.height);
    const double most = std::min(supersampledPixelBudget(camera.width(), camera.height()), budget.itemsWithin(0.5, kBytesPerPixel));
    s.factor = std::max(1, std::min(wanted, int(std::floor(std::sqrt(most / pixels)))));
    // Tiles' lattices follow the sub-pixels: at most tileKernelBudget of their kernels (the
    // count grows with the factor; without sub-pixels they make what they make).
    const double tileBudget = tileKernelBudget(camera.width(), camera.height());
    const auto tilesFit = [&](int factor) {
        return tileKernels(grid, camera.window(s.x0, s.y0, s.width, s.height, factor), settings, tileBudget) <= tileBudget;
    };
    if (s.factor > 1 && !tilesFit(s.factor)) {
        int lo = 1, hi = s.factor; // tilesFit(hi) is false; lo fits or is 1
        while (hi - lo > 1) {
            const int mid = (lo + hi) / 2;
            (tilesFit(mid) ? lo : hi) = mid;
        }
        s.factor = lo;
        s.tileLimited = true;
    }
    if (s.factor < wanted && !s.tileLimited) {
        std::ostringstream w;
        w << "--supersample lowered from " << wanted << " to " << s.factor << " sub-pixels a pixel side: " << s.width << "x" << s.height
          << " pixels at " << wanted << "x" << wanted << " would pass " << std::llround(most) << " sub-pixels (16 images, or half of --max-memory); "
          << "the volume's voxels span " << px << " pixels, so its edges and fine detail render more opaque than a camera's average";
        warnings.push_back(w.str());
    }
    if (s.factor == 1) return one;
    const double fadeFrom = (1.0 - kBlendShare) * settings.splat.supersampleSpan;
    if (s.factor == 2 && px > fadeFrom) s.blend = std::min(1.0, (px - fadeFrom) / (kBlendShare * settings.splat.supersampleSpan));
    return s;
}

void mixFrames(Frame& frame, const Frame& other, double weight)
{
    const float w = float(weight), keep = 1.0f - w;
    for (auto [a, b] : {std::pair{&frame.beauty.rgba, &other.beauty.rgba}, {&frame.transmittance, &other.transmittance},
             {&frame.shadow, &other.shadow}, {&frame.emission, &other.emission}}) {
        for (std::size_t i = 0; i < a->size() && i < b->size(); ++i) (*a)[i] = keep * (*a)[i] + w * (*b)[i];
    }
    if (weight > 0.5) frame.depth = other.depth;
}

Frame boxFiltered(const Frame& sub, const Supersampling& s, int width, int height, const PassRequest& passes)
{
    Frame out = blankFrame(width, height, passes);
    const int f = s.factor;
    const std::size_t subWidth = std::size_t(s.width) * std::size_t(f);
    const float weight = 1.0f / float(f * f);
    tbb::parallel_for(0, s.height, [&](int j) {
        std::vector<float> depths(std::size_t(f) * std::size_t(f));
        for (int i = 0; i < s.width; ++i) {
            const std::size_t o = std::size_t(s.y0 + j) * std::size_t(width) + std::size_t(s.x0 + i);
            float rgba[4] = {0, 0, 0, 0}, t[3] = {0, 0, 0}, shadow[3] = {0, 0, 0}, emission[3] = {0, 0, 0};
            std::size_t n = 0;
            for (int b = 0; b < f; ++b) {
                for (int a = 0; a < f; ++a) {
                    const std::size_t q = (std::size_t(j) * std::size_t(f) + std::size_t(b)) * subWidth + std::size_t(i) * std::size_t(f) + std::size_t(a);
                    for (int c = 0; c < 4; ++c) rgba[c] += sub.beauty.rgba[4 * q + std::size_t(c)];
                    for (int c = 0; c < 3; ++c) {
                        if (passes.transmittance) t[c] += sub.transmittance[3 * q + std::size_t(c)];
                        if (passes.shadow) shadow[c] += sub.shadow[3 * q + std::size_t(c)];
                        if (passes.emission) emission[c] += sub.emission[3 * q + std::size_t(c)];
                    }
                    if (passes.depth) depths[n++] = sub.depth[q];
                }
            }
            for (int c = 0; c < 4; ++c) out.beauty.rgba[4 * o + std::size_t(c)] = rgba[c] * weight;
            for (int c = 0; c < 3; ++c) {
                if (passes.transmittance) out.transmittance[3 * o + std::size_t(c)] = t[c] * weight;
                if (passes.shadow) out.shadow[3 * o + std::size_t(c)] = shadow[c] * weight;
                if (passes.emission) out.emission[3 * o + std::size_t(c)] = emission[c] * weight;
            }
            if (passes.depth) {
                // The lower median: finite where at least half the sub-pixels reach alpha 0.5.
                const auto mid = depths.begin() + std::ptrdiff_t((n - 1) / 2);
                std::nth_element(depths.begin(), mid, depths.begin() + std::ptrdiff_t(n));
                out.depth[o] = *mid;
            }
        }
    });
    return out;
}

} // namespace detail
} // namespace vdb_ewa
