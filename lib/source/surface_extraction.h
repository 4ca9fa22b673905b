/// @file surface_extraction.h
/// @brief Level-set voxels next to the iso-surface -> flattened (surface) kernels
///        (Zwicker et al. 2002, Sec. 6.3, 6.4; docs/equations.md#surface-kernels).
#pragma once

#include <vdb_ewa/render_settings.h>

#include "source/grid_source_impl.h"
#include "support/huge_page_allocator.h"
#include "support/progress.h"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// A line of a kernel's tangent plane where the surface folds away (a convex crease): the
/// kernel's disc keeps the side u . (q - pWorld) <= distance (docs/equations.md#surface-coverage).
struct DiscClip
{
    glm::vec3 direction{0.0f}; ///< unit, in the tangent plane, pointing across the crease
    float distance = 0.0f;     ///< world units from the centre, >= 0
};

/// A 2D Gaussian in the tangent plane of the iso-surface (the limit of Eq. 37).
struct SurfaceKernel
{
    Vec3d pWorld;   ///< centre on the iso-surface (a Newton step from the voxel centre)
    Vec3d normal;   ///< unit world normal, the gradient direction (outwards for level sets)
    double area;    ///< surface area the kernel stands for, world^2 (its weight)
    Vec3d albedo{1.0}; ///< material colour: the colour grid at pWorld (trilinear), else white
    double discRadius = 0;           ///< world units: reaches the neighbours' discs (coverage)
    std::array<DiscClip, 3> clips{}; ///< the nearest creases across the disc, clipCount of them
    int clipCount = 0;
};

struct SurfaceSet
{
    LargeArray<SurfaceKernel> kernels; ///< in tree order (deterministic)
    double sigma = 0;                   ///< tangential std. deviation, world units
    int lattice = 1;                    ///< one kernel a lattice^3 block of voxels, per sheet (level of detail)
    double spacing = 0;                 ///< world length of a lattice step: voxel length x lattice
    Vec3d boundsMin{0.0}, boundsMax{0.0}; ///< world box of the active voxels (position shader)
    std::uint64_t activeVoxels = 0;
};

/// A voxel keeps its kernel when its Newton step onto the surface stays within this many voxels
/// of its centre along every index axis. A level set's band is active on both sides of its
/// surface, so one kernel per cell is enough, 0.5: the discs reach their neighbours' (0.5
/// halves the kernels and the time against 1, with no hole in the tests). A fog volume is
/// active only inside: where the density steps from 1 to 0, the last voxel's step to
/// --iso 0.5 is a whole voxel, and with 0.5 a ball's faces along the axes had no kernel. So
/// fog --iso surfaces keep the steps within 1 voxel.
constexpr double kReachForDiscs = 0.5, kReachForFog = 1.0;

/// What extractSurfaceKernels builds.
struct SurfaceRequest
{
    double isovalue = 0.0;
    double kernelSigma = SurfaceOptions().sigma; ///< tangential standard deviation, voxels (lattice steps)
    bool outwardDecreasing = false; ///< fog volumes: the normal is minus the gradient
    double reach = kReachForDiscs;  ///< voxels from a kernel's voxel to its point on the surface
    int lattice = 1;                ///< level of detail: a power of two dividing 8
    /// Kernels for which this is false get no area, disc or clips, as they will not be drawn
    /// (back faces); they are still their neighbours' neighbours, so the others are unchanged.
    /// Empty: every kernel is drawn.
    std::function<bool(const SurfaceKernel&)> drawn;
    /// Called with each leaf node's world box, widened by the neighbours' reach (the lattice
    /// steps within which kernels are related); false: the leaf makes no kernels, as none of
    /// them is drawn or is the neighbour of one that is (the caller widens the box by its
    /// footprints' reach). Empty: every leaf.
    std::function<bool(const Vec3d& lo, const Vec3d& hi)> leafMayBeSeen;
};

/// One kernel for every active voxel whose 6-neighbourhood crosses the isovalue and whose
/// projection onto the surface value == isovalue
/// (x - (f(x) - iso) grad / |grad|^2, central differences) lies within `reach` voxels of its
/// centre along each index axis; its area is the inverse of the kernels' density around it
/// on the surface, so that the kernels sum to one over the surface; its disc (the coverage
/// test) reaches its 8th nearest neighbour on the surface, at most kDiscRadiusSigmas sigma, and
/// is clipped where a neighbour's tangent plane, turned by more than 40 degrees, cuts it past
/// a convex crease (docs/equations.md#surface-coverage); tangential sigma = kernelSigma voxel
/// lengths. Anisotropic voxels use the voxel length cbrt|det A|. Voxels farther than 2 voxels
/// from the surface by the estimate |f - iso| / |grad f| are skipped, as are NaN values.
/// outwardDecreasing: the surface's outside is where values fall (fog volumes: the normal is
/// minus the gradient); level sets grow outwards (the normal is the gradient).
/// lattice: level of detail. Of the kernels above, each block of lattice^3 voxels keeps the
/// one nearest its centre for each sheet through it (normals more than 40 degrees apart, at
/// most kMaxSheetsPerBlock), and the rules that follow (areas, discs, clips) hold in lattice
/// steps: the neighbours are looked up by block, the sigma, the normal offsets and the crease
/// margin are lattice x what they are for voxels.
/// @a progress: one unit per leaf node; throws Cancelled.
SurfaceSet extractSurfaceKernels(const GridSource::Impl& grid, const SurfaceRequest& request, Progress* progress = nullptr);

/// The largest lattice of the level of detail: 4 (a kernel for 16 voxels of surface).
constexpr int kMaxSurfaceLattice = 4;
/// Sheets (normals more than 40 degrees apart) a level-of-detail block keeps a kernel for.
constexpr int kMaxSheetsPerBlock = 4;

/// Largest radius of a surface kernel's disc (the coverage test) in tangential standard
/// deviations; also the radius where a kernel has fewer neighbours than its rule needs. The
/// kernels stand at most about one voxel apart on the surface (sigma = 0.55 voxels): discs of
/// 3 sigma = 1.65 voxels overlap their neighbours' and close every gap.
constexpr double kDiscRadiusSigmas = 3.0;

} // namespace detail
} // namespace vdb_ewa
