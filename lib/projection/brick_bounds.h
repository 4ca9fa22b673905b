/// @file brick_bounds.h
/// @brief Where a brick's splats can land before any of its kernels exist: the pixels they can
///        touch and the first slab they can start in, conservative bounds the streamed
///        frame orders and culls bricks by (docs/architecture.md#the-streamed-frame).
#pragma once

#include "source/source.h"

#include <vdb_ewa/camera.h>
#include <vdb_ewa/slab_share.h>

#include <cstdint>

namespace vdb_ewa {
namespace detail {

struct BrickBounds
{
    /// Some splat of the brick can reach the image.
    bool visible = true;
    /// Inclusive pixels its splats can touch: the whole image where the brick reaches the near
    /// plane or comes so close to the eye that the projection's near clamp may apply.
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
    std::int64_t nearestSlab = 0;             ///< no splat of the brick starts in front of this slab
};

/// What bounds every brick of a frame shares: the camera, the kernels' reach and the slabs.
class BrickBounder
{
public:
    /// For grids with an affine index-to-world map (GridSource::Impl::linear).
    BrickBounder(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings, const LevelOfDetail* lod,
        const SlabGrid& slabs);
    BrickBounds bound(const Brick& brick) const;

private:
    const GridSource::Impl& mGrid;
    const Camera& mCamera;
    const RenderSettings& mSettings;
    const LevelOfDetail* mLod;
    SlabGrid mSlabs;
    double mReachSigmas;  ///< a kernel's splat ends this many standard deviations from its centre (cut-off, depth)
    double mStretch;      ///< the index-to-world map's condition number: how far a sphere's image leaves it
    double mFilterPixels; ///< the low-pass filter's reach in pixels
    double mMaxTan[2];    ///< the projection's frustum clamp (1.3 x the edge), tan x and tan y
    double mMotionPad;    ///< motion blur: how far a kernel's splat can move and stretch, index units
};

} // namespace detail
} // namespace vdb_ewa
