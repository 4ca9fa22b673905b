/// @file render_stats.h
/// @brief What a render read, culled and splatted, and how long each stage took: plain data
///        that the renderer fills (Renderer::renderFrame) and the stages add to.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vdb_ewa {

/// What a render read, culled and splatted, and how long each stage took (seconds).
struct RenderStats
{
    double kernelSeconds = 0;   ///< active voxels and tiles -> reconstruction kernels
    double shadowSeconds = 0;   ///< the light map (shadow rays through the field)
    double projectSeconds = 0;  ///< kernels -> screen-space splats (Eq. 29-33) and binning
    double rasterSeconds = 0;   ///< per-tile slab compositing
    std::uint64_t activeVoxels = 0;
    std::uint64_t activeTiles = 0;
    std::uint64_t kernels = 0;        ///< kernels built (voxels + tile kernels + halo kernels)
    std::uint64_t haloKernels = 0;    ///< negative kernels beside the support (--prefilter)
    std::uint64_t emitterKernels = 0; ///< kernels of the emission and temperature grids (included in kernels)
    std::uint64_t refinedVoxels = 0;  ///< voxels sampled on the finer lattice (--refine)
    std::uint64_t kernelsSkipped = 0; ///< below the density cutoff, or invalid values
    std::uint64_t voxelsMerged = 0;   ///< active voxels merged into level-of-detail kernels (--lod)
    std::uint64_t mergedKernels = 0;  ///< the level-of-detail kernels they became
    std::uint64_t movingKernels = 0;  ///< motion blur: kernels that move over the shutter (before splitting)
    std::uint64_t motionSubKernels = 0; ///< motion blur: kernels added by splitting long paths (included in kernels)
    int surfaceLattice = 1;           ///< level sets: one surface kernel a n^3 block of voxels, per sheet (--lod)
    std::uint64_t kernelsCulled = 0;  ///< outside the view frustum
    std::uint64_t splats = 0;         ///< kernels splatted
    std::uint64_t splatTilePairs = 0; ///< (splat, screen tile) pairs binned
    std::uint64_t screenTiles = 0;         ///< 16x16 screen tiles
    std::uint64_t screenTilesOpaque = 0;   ///< tiles that turned opaque before their last splat
    std::uint64_t splatTilePairsSkipped = 0; ///< pairs skipped because their tile was opaque
    std::uint64_t footprintSamples = 0; ///< fog volumes: footprint weights evaluated (pixels inside a cut-off)
    /// Of them, those at each image level (SplatOptions::imageLod): every pixel, every 2nd, 4th
    /// and 8th pixel of a screen tile.
    std::uint64_t footprintSamplesAtLevel[4] = {0, 0, 0, 0};
    std::uint64_t slabComposites = 0;   ///< fog volumes: (pixel, slab) samples composited
    /// Of them, those at each image level (SplatOptions::imageLodComposite): at the pixels, at
    /// every 2nd, 4th and 8th pixel of a screen tile.
    std::uint64_t slabCompositesAtLevel[4] = {0, 0, 0, 0};
    bool streamed = false;            ///< fog volumes: the streamed frame ran (RenderSettings::cull)
    int supersample = 1;              ///< fog volumes: sub-pixels a pixel side the frame was composited at (SplatOptions::supersample)
    int supersampleWindow[4] = {0, 0, 0, 0}; ///< fog volumes, supersampled: the pixels x0, y0, width, height composited so
    double voxelPixels = 0;           ///< fog volumes: the active voxels' median screen size, pixels (0: not measured);
                                      ///< with --pixel-size and no sub-pixels, the median of those in view
                                      ///< (detail::voxelPixelsInView), which chose the pixel size
    int pixelSize = 1;                ///< fog volumes: the n x n pixels one sample covered (SplatOptions::pixelSize)
    std::uint64_t bricks = 0;         ///< streamed frame: leaf nodes and active tiles of the grid
    std::uint64_t bricksOutside = 0;  ///< streamed frame: bricks no splat of which reaches the image
    std::uint64_t bricksHidden = 0;   ///< streamed frame: bricks behind opaque screen tiles, never expanded
    std::uint64_t bricksExpanded = 0; ///< streamed frame: bricks whose kernels were built
    std::uint64_t windows = 0;        ///< streamed frame: depth windows composited
    std::uint64_t splatsInFlight = 0; ///< streamed frame: the most splats one window composited (what its memory holds)
    std::uint64_t lightRays = 0;      ///< light-map rays of all lights' lattices
    std::uint64_t lightRaysMarched = 0; ///< of them, marched by this render (all but where light on demand needed none: the streamed frame, a whole frame whose maps outgrow it, and a Scene's rays marched before)
    std::uint64_t lightMapsReused = 0;  ///< a Scene's renders: light maps (directional and point) kept from an earlier render (Scene)
    std::uint64_t lightRaysReused = 0;  ///< a Scene's renders: rays of those maps that earlier renders marched
    /// A progressive render's coarse image (Scene::render with a ProgressiveCallback): one
    /// sample an n x n block of pixels, interpolated; 1: the image of the asked settings.
    int coarseScale = 1;
    /// The process's peak resident memory when the render ended (peakResidentBytes(): what the
    /// render held at most, with the process's own, and earlier renders' where they held more).
    std::uint64_t peakResidentBytes = 0;
    std::string rasterBackend = "scalar"; ///< fog volumes: the slab compositor that ran ("scalar", or the SIMD target: "AVX3" (AVX-512), "AVX2")
    std::vector<std::string> warnings; ///< what was clamped or skipped, one line each
};

} // namespace vdb_ewa
