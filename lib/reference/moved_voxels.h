/// @file moved_voxels.h
/// @brief Motion blur in the reference: where the material at a point of a shutter time came
///        from. Each voxel of the still field moves with the velocity at its centre, as the
///        splatter's kernels do (docs/equations.md#motion-blur); a point is material where a
///        moved voxel's trilinear tent covers it, and it came from the point its covering
///        voxels' mean velocity takes back to the frame's time. Unlike a lookup of the velocity
///        at the point itself, this finds material wherever it moves, also where the velocity
///        grid is empty (a simulation's velocities stop where its density does).
#pragma once

#include "source/source.h"
#include "support/memory_budget.h"
#include "support/openvdb_point_index.h"
#include "support/progress.h"

#include <vdb_ewa/render_settings.h>

#include <optional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The active voxels of @a occupancy (tiles voxelised), each with its velocity in index units
/// per unit of MotionBlur::displacementPerVelocity, indexed per slice of the shutter by where
/// they are at the slice's mid-time (openvdb::tools::PointIndexGrid, a cell per voxel).
class MovedVoxels
{
public:
    /// @a occupancy: the voxels that move (the density's and the emitters' active voxels, in
    /// @a grid's index space). Velocities as the splatter samples them (VelocitySampler at each
    /// voxel centre, travel clamped to kMaxTravelVoxels). The shutter is cut into slices short
    /// enough that no voxel moves more than half a voxel from its slice's position, as many as
    /// a quarter of @a budget holds (then the lookups search further). @throw BudgetError;
    /// Cancelled (@a progress is checked between slices).
    MovedVoxels(const GridSource::Impl& grid, const openvdb::FloatGrid& occupancy, const RenderSettings& settings,
        const MemoryBudget& budget, const Progress* progress);

    std::size_t voxels() const { return mPosition.size(); }
    int slices() const { return int(mSlices.size()); }
    /// How far (index units, per axis) a voxel can be from its slice's position.
    double slack() const { return mSlack; }

    /// One thread's lookups.
    class Finder
    {
    public:
        explicit Finder(const MovedVoxels& voxels);
        /// The still field's index point the material at @a pIndex came from at shutter time
        /// @a time (MotionBlur::displacementPerVelocity), x = p - w t with w the mean index
        /// velocity of the voxels whose moved tents cover p, weighted by their tents; false where
        /// none covers it.
        bool origin(const Vec3d& pIndex, double time, Vec3d& from);

    private:
        const MovedVoxels& mVoxels;
        std::vector<std::optional<openvdb::tools::PointIndexGrid::ConstAccessor>> mAccessors;
        openvdb::tools::PointIndexIterator<openvdb::tools::PointIndexTree> mFound;
    };

private:
    std::vector<openvdb::Vec3i> mPosition;   ///< still voxel coordinates
    std::vector<openvdb::Vec3f> mVelocity;   ///< index units per unit of time
    std::vector<openvdb::tools::PointIndexGrid::Ptr> mSlices;
    double mOpen = 0.0, mSliceLength = 1.0;  ///< the shutter's start and each slice's length (time units)
    double mSlack = 0.0;
};

} // namespace detail
} // namespace vdb_ewa
