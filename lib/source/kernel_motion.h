/// @file kernel_motion.h
/// @brief Motion blur in the source stage: each kernel moves linearly over the shutter with
///        the velocity at its centre, a Gaussian convolved with a box along its path
///        (docs/equations.md#motion-blur). The kernel's path is handed to the projection
///        as plain data (KernelSet::motion); long paths are split into sub-kernels.
#pragma once

#include <vdb_ewa/camera.h>
#include <vdb_ewa/render_settings.h>

#include "source/grid_source_impl.h"
#include "source/kernel_extraction.h"
#include "support/memory_budget.h"
#include "support/rgb.h"

#include <cstdint>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// At most this many sub-kernels a kernel; longer paths make longer sub-paths (counted).
inline constexpr int kMaxSubKernels = 64;
/// A kernel travels at most this many voxel lengths over the shutter (absurd velocities are
/// clamped, and counted).
inline constexpr double kMaxTravelVoxels = 4096.0;

/// The bound on motion both integrators share: a point moves at most kMaxTravelVoxels voxel
/// lengths of its grid from the frame's time over the shutter; faster velocities are slowed to it.
class TravelLimit
{
public:
    TravelLimit(const GridSource::Impl& grid, const MotionBlur& blur);
    /// Slows @a v (world units per second or frame) to the bound; true if it had to.
    bool clamp(Vec3d& v) const;
    /// The fastest velocity within the bound.
    double fastest() const { return mMaxTravel / mReach; }

private:
    double mReach;     ///< the largest displacement per velocity from the frame's time (MotionBlur)
    double mMaxTravel; ///< world units
};

/// The velocity grid's vectors in world units per second or frame, as stored times
/// GridSource::Impl::velocityToWorld, trilinear; staggered (MAC) grids as such, each component
/// at its face and from the active faces alone; non-finite components read as 0. One per thread.
class VelocitySampler
{
public:
    explicit VelocitySampler(const GridSource::Impl& grid);
    Vec3d at(const Vec3d& pWorld);
    /// at() the density grid's index point @a pIndex (a voxel's own vector where the velocity
    /// grid shares the density's lattice and @a pIndex is a voxel centre).
    Vec3d atIndex(const Vec3d& pIndex);

private:
    /// A staggered grid's vector at index point @a p, each component from its active faces.
    openvdb::Vec3s staggered(const openvdb::Vec3d& p);

    const GridSource::Impl& mGrid;
    openvdb::Vec3SGrid::ConstAccessor mAccessor;
    bool mStaggered;
    bool mOnLattice; ///< not staggered, and the density's transform
};

/// What moveKernels counted.
struct MotionStats
{
    std::uint64_t moving = 0;     ///< kernels that move over the shutter
    std::uint64_t subKernels = 0; ///< kernels added by splitting long paths
    std::uint64_t longPaths = 0;  ///< kernels whose path needed more than kMaxSubKernels
    std::uint64_t clamped = 0;    ///< kernels whose travel was clamped to kMaxTravelVoxels
};

/// The velocity at every kernel's centre (VelocitySampler), in kernel order: what the
/// sub-frames of one sweep share (moveKernels' @a velocities). Empty without a velocity grid.
std::vector<Vec3d> kernelVelocities(const GridSource::Impl& grid, const KernelSet& kernels);

/// Motion blur: every kernel of @a kernels moved to its centre at the shutter's mid-time and
/// given its path over the shutter (KernelSet::motion); a path whose image through @a camera
/// is longer than MotionBlur::splitSigmas of the kernel's filtered footprint along it is split
/// into that many sub-kernels, each a share of the weight over an equal part of the path (@a colors,
/// KernelSet::emitted and emitterBegin follow). Nothing changes without a velocity grid.
/// @a budget: the sub-kernels are counted before they are allocated (BudgetError).
/// @a velocities: kernelVelocities(grid, kernels), where already sampled (null: sampled here).
MotionStats moveKernels(const GridSource::Impl& grid, const RenderSettings& settings, const Camera& camera, KernelSet& kernels,
    std::vector<Rgb>& colors, const MemoryBudget* budget, const std::vector<Vec3d>* velocities = nullptr);

/// How far any kernel of @a grid can be from its still centre over the shutter, at most, in
/// world units (the velocity grid's largest vector): what the streamed frame's brick bounds
/// grow by. 0 without a velocity grid.
double largestTravel(const GridSource::Impl& grid, const RenderSettings& settings);

/// The velocity grid's largest vector in world units per second or frame (unscaled), 0 without one.
double fastestVelocity(const GridSource::Impl& grid);

/// A warning where the fastest voxel's path over the shutter is longer than the volume's
/// largest side (an absurd blur: velocities in another unit than the options say), naming the
/// options that fix it (for a Blender Mantaflow cache, the scale its unit needs); empty otherwise.
std::string longPathWarning(const GridSource::Impl& grid, const RenderSettings& settings);

} // namespace detail
} // namespace vdb_ewa
