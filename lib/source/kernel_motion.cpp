/// @file kernel_motion.cpp
#include "source/kernel_motion.h"

#include "support/openvdb_tools.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace vdb_ewa {
namespace detail {

namespace {

/// A stored velocity in world units per second or frame, non-finite components as 0.
Vec3d worldVelocity(const GridSource::Impl& grid, const openvdb::Vec3s& v)
{
    Vec3d out(0.0);
    for (int a = 0; a < 3; ++a) out[a] = std::isfinite(v[a]) ? double(v[a]) : 0.0;
    return grid.velocityToWorld * out;
}

} // namespace

TravelLimit::TravelLimit(const GridSource::Impl& grid, const MotionBlur& blur)
    : mReach(std::max({std::abs(blur.displacementPerVelocity(blur.shutterOpen)), std::abs(blur.displacementPerVelocity(blur.shutterClose)), 1e-300})),
      mMaxTravel(kMaxTravelVoxels * grid.voxelLength)
{
}

bool TravelLimit::clamp(Vec3d& v) const
{
    const double speed = glm::length(v);
    if (!(speed * mReach > mMaxTravel)) return false;
    v *= mMaxTravel / (speed * mReach);
    return true;
}

VelocitySampler::VelocitySampler(const GridSource::Impl& grid)
    : mGrid(grid), mAccessor(grid.velocity->getConstAccessor()), mStaggered(grid.velocity->getGridClass() == openvdb::GRID_STAGGERED),
      mOnLattice(!mStaggered && grid.velocity->transform() == grid.grid->transform())
{
}

Vec3d VelocitySampler::atIndex(const Vec3d& pIndex)
{
    // A velocity grid on the density's lattice, at a voxel centre: the voxel's own vector,
    // what the trilinear sample there weighs 1 (no transform, one lookup instead of eight).
    if (mOnLattice) {
        const openvdb::Coord ijk(int(std::lround(pIndex.x)), int(std::lround(pIndex.y)), int(std::lround(pIndex.z)));
        if (Vec3d(ijk.x(), ijk.y(), ijk.z()) == pIndex) return worldVelocity(mGrid, mAccessor.getValue(ijk));
    }
    return at(mGrid.indexToWorld(pIndex));
}

Vec3d VelocitySampler::at(const Vec3d& pWorld)
{
    const openvdb::Vec3d p = mGrid.velocity->transform().worldToIndex(openvdb::Vec3d(pWorld.x, pWorld.y, pWorld.z));
    openvdb::Vec3s v(0.0f);
    if (mStaggered) v = staggered(p);
    else openvdb::tools::BoxSampler::sample(mAccessor, p, v);
    return worldVelocity(mGrid, v);
}

openvdb::Vec3s VelocitySampler::staggered(const openvdb::Vec3d& p)
{
    // OpenVDB's staggered layout (StaggeredBoxSampler): component a of voxel ijk sits at the face
    // ijk - e_a / 2, so it is read trilinearly at p + e_a / 2. A cache clipped to its density
    // (Mantaflow's) leaves the outer faces of its boundary cells in inactive voxels: their
    // values are unknown, not 0, so each component weighs its active faces alone (a boundary
    // cell's face would otherwise halve its speed out of the material).
    openvdb::Vec3s v(0.0f);
    for (int a = 0; a < 3; ++a) {
        openvdb::Vec3d q = p;
        q[a] += 0.5;
        const openvdb::Coord lo = openvdb::Coord::floor(q);
        const openvdb::Vec3d f = q - lo.asVec3d();
        double sum = 0.0, weight = 0.0;
        for (int corner = 0; corner < 8; ++corner) {
            const openvdb::Coord c = lo + openvdb::Coord(corner & 1, (corner >> 1) & 1, corner >> 2);
            const double w = ((corner & 1) ? f.x() : 1.0 - f.x()) * (((corner >> 1) & 1) ? f.y() : 1.0 - f.y()) * ((corner >> 2) ? f.z() : 1.0 - f.z());
            openvdb::Vec3s value;
            if (!(w > 0.0) || !mAccessor.probeValue(c, value)) continue;
            sum += w * double(value[a]);
            weight += w;
        }
        v[a] = weight > 0.0 ? float(sum / weight) : mAccessor.getValue(lo)[a]; // no active face: the background
    }
    return v;
}

namespace {

/// The smallest eigenvalue of the symmetric positive semi-definite @a m (closed form, Smith 1961).
double leastEigenvalue(const Mat3d& m)
{
    const double p1 = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
    const double q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
    if (p1 == 0.0) return std::min({m[0][0], m[1][1], m[2][2]});
    const double p2 = (m[0][0] - q) * (m[0][0] - q) + (m[1][1] - q) * (m[1][1] - q) + (m[2][2] - q) * (m[2][2] - q) + 2.0 * p1;
    const double p = std::sqrt(p2 / 6.0);
    const Mat3d b = (m - Mat3d(q)) / p;
    const double r = std::clamp(glm::determinant(b) / 2.0, -1.0, 1.0);
    const double phi = std::acos(r) / 3.0;
    return q + 2.0 * p * std::cos(phi + 2.0 * 3.14159265358979323846 / 3.0);
}

/// A kernel's motion before it is split: its velocity's travel to the mid-time and over the
/// shutter (world units), and the sub-kernels it needs.
struct Travel
{
    Vec3d shift{0.0}, path{0.0};
    int pieces = 1;
    bool clamped = false, longPath = false;
};

} // namespace

std::vector<Vec3d> kernelVelocities(const GridSource::Impl& grid, const KernelSet& kernels)
{
    if (!grid.velocity) return {};
    std::vector<Vec3d> out(kernels.kernels.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        VelocitySampler velocity(grid);
        for (std::size_t i = range.begin(); i < range.end(); ++i) out[i] = velocity.atIndex(kernels.kernels[i].pIndex);
    });
    return out;
}

MotionStats moveKernels(const GridSource::Impl& grid, const RenderSettings& settings, const Camera& camera, KernelSet& kernels,
    std::vector<Rgb>& colors, const MemoryBudget* budget, const std::vector<Vec3d>* velocities)
{
    MotionStats stats;
    kernels.motion.clear();
    if (!grid.velocity || kernels.kernels.empty()) return stats;
    const std::vector<Vec3d> sampled = velocities ? std::vector<Vec3d>() : kernelVelocities(grid, kernels);
    const std::vector<Vec3d>& velocity = velocities ? *velocities : sampled;
    const MotionBlur& blur = settings.motionBlur;
    const double open = blur.displacementPerVelocity(blur.shutterOpen), close = blur.displacementPerVelocity(blur.shutterClose);
    const double mid = 0.5 * (open + close), length = close - open;
    const TravelLimit limit(grid, blur);
    // The kernel's narrowest world extent per voxel of sigma: the index-to-world map's smallest
    // singular value (conservative for sheared and anisotropic voxels: more sub-kernels).
    const Mat3d ata = glm::transpose(grid.indexToWorldLinear) * grid.indexToWorldLinear;
    const double narrowest = std::sqrt(std::max(0.0, leastEigenvalue(ata)));
    const bool perspective = camera.projection() == Projection::Perspective;
    const double f = camera.focalPixels(), lowpass = settings.splat.lowpass;
    const Mat3d R = camera.cameraFromWorld();
    const std::size_t n = kernels.kernels.size();
    std::vector<Travel> travel(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const Kernel& k = kernels.kernels[i];
            const Vec3d pWorld = grid.indexToWorld(k.pIndex);
            Vec3d v = velocity[i];
            Travel& t = travel[i];
            if (!(glm::length(v) > 0.0)) continue;
            t.clamped = limit.clamp(v); // absurd velocities
            t.shift = v * mid;
            t.path = v * length;
            // The path's image in pixels (the projection's Jacobian at the mid-time centre) and
            // the footprint's width along it, the low-pass filter's at least (Eq. 33).
            // Where the mid-time centre is not in front of the near plane: the path's length
            // against the kernel's own width (no pixel to measure in).
            const Vec3d c = camera.cameraFromWorldPoint(pWorld + t.shift), d = R * t.path;
            double pixels = glm::length(d), pixelsPerUnit = 1.0, floor = 0.0;
            if (perspective && c.z > camera.near()) {
                pixelsPerUnit = f / c.z;
                pixels = pixelsPerUnit * std::hypot(d.x - c.x / c.z * d.z, d.y - c.y / c.z * d.z);
                floor = lowpass;
            } else if (!perspective) {
                pixelsPerUnit = f;
                pixels = f * std::hypot(d.x, d.y);
                floor = lowpass;
            }
            const double sigmaPixels = kernelSigmaVoxels(k, settings.splat.kernelSigma) * narrowest * pixelsPerUnit;
            const double footprint = std::sqrt(std::max(sigmaPixels * sigmaPixels, floor));
            double pieces = std::ceil(pixels / (blur.splitSigmas * footprint));
            if (!(pieces >= 1.0)) pieces = 1.0; // also NaN (a degenerate transform)
            t.longPath = pieces > double(kMaxSubKernels);
            t.pieces = int(std::clamp(pieces, 1.0, double(kMaxSubKernels)));
            // Shutter layers: each piece's time within one layer, or spread evenly over the
            // layers it covers (a divisor of their number), so each layer holds its exact share.
            const int layers = blur.layers;
            if (layers > 1 && t.pieces > 1) {
                if (t.pieces < layers) {
                    while (layers % t.pieces) ++t.pieces;
                } else {
                    t.pieces = std::min((t.pieces + layers - 1) / layers * layers, kMaxSubKernels / layers * layers);
                }
            }
        }
    });
    std::vector<std::size_t> first(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const Travel& t = travel[i];
        stats.moving += (t.path != Vec3d(0.0) || t.shift != Vec3d(0.0));
        stats.clamped += t.clamped;
        stats.longPaths += t.longPath;
        first[i + 1] = first[i] + std::size_t(t.pieces);
    }
    if (stats.moving == 0) return stats; // still: the frame stays bit-identical to one without blur
    const std::size_t total = first[n];
    stats.subKernels = total - n;
    if (budget && total > n) budget->check(double(total), "kernels with motion blur's sub-kernels", kBytesPerKernel);

    LargeArray<Kernel> split(total);
    LargeArray<KernelMotion> motion(total);
    std::vector<Rgb> splitColors(colors.empty() ? 0 : total);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            const Travel& t = travel[i];
            const int m = t.pieces;
            const int layers = blur.layers;
            for (int j = 0; j < m; ++j) {
                // Sub-path j of m: its centre (j + 1/2)/m along the path, a share 1/m of the weight.
                Kernel k = kernels.kernels[i];
                k.density /= float(m);
                const Vec3d shift = t.shift + t.path * ((double(j) + 0.5) / double(m) - 0.5), path = t.path / double(m);
                const std::size_t at = first[i] + std::size_t(j);
                split[at] = k;
                motion[at] = KernelMotion{{float(shift.x), float(shift.y), float(shift.z)}, {float(path.x), float(path.y), float(path.z)}};
                // Its time, [j, j + 1] / m of the shutter, covers layers floor(j L / m) to
                // ceil((j + 1) L / m) - 1 of L (docs/equations.md#shutter-layers).
                const int first = j * layers / m, last = ((j + 1) * layers + m - 1) / m - 1;
                if (last - first + 1 < layers) {
                    motion[at].layerFirst = std::uint16_t(first);
                    motion[at].layerCount = std::uint16_t(last - first + 1);
                }
                if (!colors.empty()) splitColors[at] = colors[i];
            }
        }
    });
    if (kernels.emitterBegin < n) {
        std::vector<std::array<float, 3>> emitted;
        emitted.reserve(total - first[kernels.emitterBegin]);
        for (std::size_t i = kernels.emitterBegin; i < n; ++i) emitted.insert(emitted.end(), std::size_t(travel[i].pieces), kernels.emitted[i - kernels.emitterBegin]);
        kernels.emitted = std::move(emitted);
        kernels.emitterBegin = first[kernels.emitterBegin];
    }
    kernels.kernels = std::move(split);
    kernels.motion = std::move(motion);
    if (!colors.empty()) colors = std::move(splitColors);
    return stats;
}

double fastestVelocity(const GridSource::Impl& grid)
{
    if (!grid.velocity) return 0.0;
    // The largest stored vector (tiles, voxels and the background) bounds the trilinear samples:
    // the tiles and the background here, the leaves' voxels in parallel.
    const auto longest = [&](const openvdb::Vec3s& v) { return glm::length(worldVelocity(grid, v)); };
    double most = longest(grid.velocity->background());
    auto tiles = grid.velocity->tree().cbeginValueAll();
    tiles.setMaxDepth(tiles.getLeafDepth() - 1);
    for (; tiles; ++tiles) most = std::max(most, longest(*tiles));
    std::vector<const openvdb::Vec3SGrid::TreeType::LeafNodeType*> leaves;
    leaves.reserve(grid.velocity->tree().leafCount());
    for (auto leaf = grid.velocity->tree().cbeginLeaf(); leaf; ++leaf) leaves.push_back(leaf.getLeaf());
    return tbb::parallel_reduce(tbb::blocked_range<std::size_t>(0, leaves.size(), 16), most,
        [&](const tbb::blocked_range<std::size_t>& range, double m) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const openvdb::Vec3s* values = leaves[i]->buffer().data();
                for (openvdb::Index v = 0; v < leaves[i]->size(); ++v) m = std::max(m, longest(values[v]));
            }
            return m;
        },
        [](double a, double b) { return std::max(a, b); });
}

double largestTravel(const GridSource::Impl& grid, const RenderSettings& settings)
{
    if (!grid.velocity) return 0.0;
    const MotionBlur& blur = settings.motionBlur;
    const double reach = std::max(std::abs(blur.displacementPerVelocity(blur.shutterOpen)), std::abs(blur.displacementPerVelocity(blur.shutterClose)));
    return std::min(fastestVelocity(grid) * reach, kMaxTravelVoxels * grid.voxelLength);
}

std::string longPathWarning(const GridSource::Impl& grid, const RenderSettings& settings)
{
    if (!grid.velocity) return {};
    const MotionBlur& blur = settings.motionBlur;
    const double path = std::min(fastestVelocity(grid), TravelLimit(grid, blur).fastest()) *
                        std::abs(blur.displacementPerVelocity(blur.shutterClose) - blur.displacementPerVelocity(blur.shutterOpen));
    const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
    if (box.empty()) return {};
    // The active box's longest side in world units (its edges through the linear map).
    const Vec3d extent = Vec3d(box.dim().x(), box.dim().y(), box.dim().z());
    double size = 0.0;
    for (int a = 0; a < 3; ++a) size = std::max(size, glm::length(grid.indexToWorldLinear[a] * extent[a]));
    if (!(path > size)) return {};
    std::ostringstream w;
    w.precision(3);
    w << "velocity grid '" << grid.velocity->getName() << "': its fastest voxel moves " << path << " units over the shutter, " << path / size
      << "x the volume's size: check --velocity-unit, --velocity-scale, --fps";
    // Blender's Mantaflow writes its velocities in cells per Mantaflow time unit, and tags its
    // grids with file_base_resolution: 2.5 voxel lengths a second at a Time Scale of 1.
    const openvdb::FloatMetadata::ConstPtr voxel = grid.velocity->getMetadata<openvdb::FloatMetadata>("file_voxel_size");
    if (grid.velocity->getGridClass() == openvdb::GRID_STAGGERED && grid.velocity->getMetadata<openvdb::Vec3IMetadata>("file_base_resolution") && voxel) {
        w << "; Mantaflow caches hold cells per its time unit: --velocity-unit second --velocity-scale " << 2.5 * double(voxel->value())
          << " (2.5 x voxel x Time Scale)";
    }
    return w.str();
}

} // namespace detail
} // namespace vdb_ewa
