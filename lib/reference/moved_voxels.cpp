/// @file moved_voxels.cpp
#include "reference/moved_voxels.h"

#include "source/source.h"

#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

namespace {

/// What one voxel costs in one slice's index (its index and its share of the leaves), rounded up.
constexpr double kBytesPerVoxelSlice = 16.0;
/// At most this many slices of the shutter.
constexpr int kMaxSlices = 1024;

/// The voxels' positions at one time, as PointIndexGrid reads a point list.
struct PositionsAt
{
    using PosType = openvdb::Vec3R;
    const std::vector<openvdb::Vec3i>& position;
    const std::vector<openvdb::Vec3f>& velocity;
    double time;
    std::size_t size() const { return position.size(); }
    void getPos(std::size_t n, PosType& xyz) const { xyz = PosType(position[n]) + PosType(velocity[n]) * time; }
};

} // namespace

MovedVoxels::MovedVoxels(const GridSource::Impl& grid, const openvdb::FloatGrid& occupancy, const RenderSettings& settings,
    const MemoryBudget& budget, const Progress* progress)
{
    const double count = double(occupancy.tree().activeVoxelCount());
    budget.check(count, "voxels moved by the reference's motion blur", sizeof(openvdb::Vec3i) + sizeof(openvdb::Vec3f) + 2.0 * kBytesPerVoxelSlice);
    mPosition.reserve(std::size_t(count));
    for (auto v = occupancy.tree().cbeginValueOn(); v; ++v) { // one point a voxel, also in tiles
        if (v.isVoxelValue()) {
            mPosition.push_back(v.getCoord().asVec3i());
        } else {
            const openvdb::CoordBBox tile = v.getBoundingBox();
            for (auto c = tile.begin(); c; ++c) mPosition.push_back((*c).asVec3i());
        }
    }

    // Velocities in index units per unit of time, their travel clamped as the splatter's is.
    const MotionBlur& blur = settings.motionBlur;
    const double open = blur.displacementPerVelocity(blur.shutterOpen), close = blur.displacementPerVelocity(blur.shutterClose);
    const TravelLimit limit(grid, blur);
    const Mat3d indexFromWorld = glm::inverse(grid.indexToWorldLinear);
    mVelocity.resize(mPosition.size());
    const double fastest = tbb::parallel_reduce(tbb::blocked_range<std::size_t>(0, mPosition.size(), 4096), 0.0,
        [&](const tbb::blocked_range<std::size_t>& range, double most) {
            VelocitySampler sampler(grid);
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                const openvdb::Vec3i& c = mPosition[i];
                Vec3d v = sampler.atIndex(Vec3d(c.x(), c.y(), c.z()));
                limit.clamp(v);
                const Vec3d w = indexFromWorld * v;
                mVelocity[i] = openvdb::Vec3f(float(w.x), float(w.y), float(w.z));
                most = std::max({most, std::abs(double(mVelocity[i].x())), std::abs(double(mVelocity[i].y())), std::abs(double(mVelocity[i].z()))});
            }
            return most;
        },
        [](double a, double b) { return std::max(a, b); });

    // Slices: a voxel is at most half a voxel from its slice's mid-time position where the
    // budget allows, further where it does not (the lookups search that much further).
    const double first = std::min(open, close), span = std::abs(close - open); // a negative scale runs backwards
    const double wanted = std::ceil(fastest * span);
    const double affordable = std::max(1.0, budget.itemsWithin(0.25, std::max(count, 1.0) * kBytesPerVoxelSlice));
    const int slices = int(std::clamp(std::min(wanted, affordable), 1.0, double(kMaxSlices)));
    mOpen = first;
    mSliceLength = span > 0.0 ? span / double(slices) : 1.0;
    mSlack = 0.5 * fastest * (span / double(slices));
    const openvdb::math::Transform::Ptr unit = openvdb::math::Transform::createLinearTransform(1.0);
    mSlices.reserve(std::size_t(slices));
    for (int k = 0; k < slices; ++k) {
        if (progress) progress->check();
        const PositionsAt at{mPosition, mVelocity, first + (double(k) + 0.5) * mSliceLength};
        mSlices.push_back(openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(at, *unit));
    }
}

MovedVoxels::Finder::Finder(const MovedVoxels& voxels) : mVoxels(voxels), mAccessors(voxels.mSlices.size()) {}

bool MovedVoxels::Finder::origin(const Vec3d& pIndex, double time, Vec3d& from)
{
    const int slices = int(mVoxels.mSlices.size());
    const int k = std::clamp(int(std::floor((time - mVoxels.mOpen) / mVoxels.mSliceLength)), 0, slices - 1);
    auto& accessor = mAccessors[std::size_t(k)];
    if (!accessor) accessor.emplace(mVoxels.mSlices[std::size_t(k)]->getConstAccessor());
    // A tent reaches one voxel from its centre; the voxels sit within the slack of their
    // slice's positions, each in the cell its position rounds to.
    const double reach = 1.0 + mVoxels.mSlack + 1e-9 * (1.0 + std::abs(time));
    const openvdb::Coord lo(int(std::lround(pIndex.x - reach)), int(std::lround(pIndex.y - reach)), int(std::lround(pIndex.z - reach)));
    const openvdb::Coord hi(int(std::lround(pIndex.x + reach)), int(std::lround(pIndex.y + reach)), int(std::lround(pIndex.z + reach)));
    mFound.searchAndUpdate(openvdb::CoordBBox(lo, hi), *accessor);
    double weight = 0.0;
    Vec3d moved(0.0);
    for (; mFound; ++mFound) {
        const std::size_t i = *mFound;
        const openvdb::Vec3i& c = mVoxels.mPosition[i];
        const openvdb::Vec3f& w = mVoxels.mVelocity[i];
        // Voxel i's trilinear tent (the field is the sum of its voxels' tents), moved to where
        // the voxel is at this time.
        double tent = 1.0;
        for (int a = 0; a < 3 && tent > 0.0; ++a) tent *= std::max(0.0, 1.0 - std::abs(pIndex[a] - double(c[a]) - double(w[a]) * time));
        if (!(tent > 0.0)) continue;
        weight += tent;
        moved += tent * Vec3d(w.x(), w.y(), w.z());
    }
    if (!(weight > 0.0)) return false;
    from = pIndex - moved * (time / weight);
    return true;
}

} // namespace detail
} // namespace vdb_ewa
