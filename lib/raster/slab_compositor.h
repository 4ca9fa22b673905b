/// @file slab_compositor.h
/// @brief The slab compositor's seam: what a backend is given for a frame (the splats in sweep
///        order, binned to tiles, and the options every tile shares) and what it returns (the
///        frame's pixels and passes, each tile's deep samples and counters). The scalar backend
///        (scalar_slab_compositor.cpp) is the test oracle of any other (SIMD, GPU).
#pragma once

#include "projection/projection.h"
#include "raster/light_on_demand.h"
#include "raster/surface_layer.h"
#include "raster/tile_bins.h"
#include "shading/shading.h"

#include <vdb_ewa/frame.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// exp(-r/2) for r in [0, rMax] in a 1D table, linearly interpolated (Sec. 7.1).
class ExpTable
{
public:
    explicit ExpTable(float rMax) : mScale(float(kSize - 1) / rMax)
    {
        for (int i = 0; i < kSize; ++i) mValues[i] = std::exp(-0.5f * float(i) / mScale);
        mValues[kSize] = mValues[kSize - 1];
    }
    float lookup(float r) const
    {
        const float x = std::min(r * mScale, float(kSize - 1));
        const int i = int(x);
        return mValues[i] + (x - float(i)) * (mValues[i + 1] - mValues[i]);
    }

private:
    static constexpr int kSize = 1024;
    float mScale;
    float mValues[kSize + 1];
};

/// A light as the compositor shades with it: its light map, and its colour x scattering
/// albedo per channel (OpticalModel::lightScale), per unit scattering weight.
struct CompositeLight
{
    const LightMap* map = nullptr;
    float scale[3] = {0.0f, 0.0f, 0.0f};
    Vec3d towards{0.0}; ///< unit direction towards the light (world): the phase function's angle
};

/// What every tile compositor of a frame shares.
struct CompositeOptions
{
    float cutoff = 0.0f;
    ExpEvaluation exp = ExpEvaluation::Incremental;
    /// Footprints less this, their value at the cut-off, with SplatOptions::taper (0: truncated).
    float taperEdge = 0.0f;
    const ExpTable* table = nullptr;
    /// Image-space level of detail (SplatOptions::imageLod, docs/equations.md#image-space-level-of-detail):
    /// a splat is accumulated at the coarsest of a tile's levels (kImageLevels) whose samples
    /// its narrowest standard deviation spans at least this many times, and each level is
    /// reconstructed bilinearly onto the pixels when its slab is composited. 0: every splat at
    /// every pixel.
    float imageLod = 0.0f;
    /// With imageLod (SplatOptions::imageLodComposite): a tile whose splats so far all lie at
    /// a coarser level than the pixels is composited and lit at that level's samples, and its
    /// colour, transmittance and passes reconstructed bilinearly at the pixels when it is
    /// finished or a finer splat arrives (docs/equations.md#compositing-at-a-coarser-level).
    /// Frames with deep samples, surfaces or shutter layers composite at the pixels.
    bool imageLodComposite = false;
    SlabGrid slabs;
    PassRequest passes;
    PassLayout layout; ///< where the shadow and emission passes' source terms are (SplatSet::passSources)
    /// Shading per slab sample (docs/numerics.md#shading-per-slab-sample): each light's
    /// transmittance at each (pixel, slab) from its light map lights the splats' scattering
    /// weights; empty when nothing scatters.
    std::vector<CompositeLight> lights;
    /// The point and spot lights that scatter (null: none), lit per slab sample from their own
    /// maps as the directional lights are, each times its falloff at the layer's middle.
    const PointLights* pointLights = nullptr;
    /// Some light lights the splats' scattering weights per slab sample.
    bool lit() const { return !lights.empty() || pointLights; }
    /// Motion blur: the splats carry their moves (SplatSet::shifts), and each slab sample's
    /// light is looked up where its material is in the still field, at most @a maxShift (world
    /// units) from where it is now.
    bool shifted = false;
    double maxShift = 0.0;
    /// Motion blur's shutter layers (MotionBlur::layers): each pixel keeps this many
    /// transmittances, and a splat's optical depth darkens the layers it covers
    /// (Splat::layerFirst, layerCount); the slab's colour is shared by them. 1: off.
    int layers = 1;
    const OpticalModel* model = nullptr;
    const Camera* camera = nullptr;
    bool tinted = false; ///< scattering weights differ from optical depths (material colours)
    bool emissive = true; ///< some splat has a pre-shaded source term (Splat::emission)
    /// An opaque or semi-opaque surface composited at its depth (fog --iso surfaces): its layer,
    /// the slab coordinate of each pixel's surface (frame order, NaN where none) and, for the
    /// shadow pass, the lights' transmittance at the surface as a layer. Null: none.
    const SurfaceLayer* surface = nullptr;
    const float* surfaceAt = nullptr;
    const SurfaceLayer* surfaceShadow = nullptr;
};

/// A tile's deep samples, grouped by tile pixel in depth order (depths still along the ray).
struct TileDeep
{
    std::uint32_t counts[kTilePixels] = {};
    std::vector<DeepSample> samples;
};

/// What a tile's sweep counted: the pairs skipped once the tile was opaque, the footprint
/// weights evaluated and the (pixel, slab) samples composited (bench/roofline's units).
struct TileCounters
{
    std::uint64_t skipped = 0, samples = 0, composites = 0;
    /// Of the samples, those of each image level (CompositeOptions::imageLod): every pixel, then
    /// every 2nd, 4th and 8th.
    std::uint64_t levelSamples[kImageLevels] = {};
    /// Of the composites, those at each image level (CompositeOptions::imageLodComposite).
    std::uint64_t levelComposites[kImageLevels] = {};
};

/// Where a streamed frame's tiles write what they finish: the frame's pixels and passes, each
/// tile's deep samples (one TileDeep per tile when asked for, else empty) and counters (one per
/// tile), and the camera depth per unit of distance along each pixel's ray (as
/// SlabCompositor::composite's).
struct StreamOutput
{
    Frame* frame = nullptr;
    const std::vector<float>* depthScale = nullptr;
    std::vector<TileDeep>* deep = nullptr;
    std::vector<TileCounters>* counters = nullptr;
};

/// A frame composited in depth windows (the streamed frame, docs/architecture.md#the-streamed-frame):
/// every tile keeps its sweep (transmittance, colour, pending slabs) from one window to the
/// next, so the frame equals the one SlabCompositor::composite makes of all the windows'
/// splats at once. The windows come front to back: a window's splats start at or behind the
/// previous window's end. A tile is written to the output once it is opaque or the last
/// window ends.
class SlabStream
{
public:
    virtual ~SlabStream() = default;
    /// Sweep a window's splats (@a bins: in the sweep order) into their tiles, then composite
    /// every slab in front of @a windowEnd (no later splat reaches one), so that opaque() tells
    /// which tiles nothing behind can change. Parallel over tiles; throws Cancelled.
    virtual void composite(const SplatSet& set, const TileBins& bins, std::int64_t windowEnd, Progress* progress) = 0;
    /// Tile t (row-major, kTileSize pixels a side) has stopped every pixel's ray.
    virtual bool opaque(int t) const = 0;
    /// Write every tile not written yet.
    virtual void finish() = 0;
};

/// One way of compositing a frame's tiles. Every tile sweeps its splats (bins: in the sweep
/// order, first slab then kernel index) front to back into slab accumulators, lit per slab
/// sample, until it is opaque, and writes its pixels and passes into @a frame (@a deep: one
/// TileDeep per tile when deep samples are asked for, else empty; @a counters: one per tile).
/// @a depthScale: camera depth per unit of distance along each pixel's ray (frame order; empty
/// unless Z, deep samples or a surface are asked for). The result must not depend on the
/// thread count. @a progress: one unit per tile; throws Cancelled.
class SlabCompositor
{
public:
    virtual ~SlabCompositor() = default;
    virtual void composite(const SplatSet& set, const TileBins& bins, const CompositeOptions& options,
        const std::vector<float>& depthScale, Frame& frame, std::vector<TileDeep>& deep, std::vector<TileCounters>& counters,
        Progress* progress) const = 0;
    /// The same compositing, window by window, into @a output; @a options and @a output must
    /// outlive the stream.
    virtual std::unique_ptr<SlabStream> stream(const CompositeOptions& options, const StreamOutput& output) const = 0;
};

/// The scalar backend carrying @a channels colour channels: 3, or 1 when every splat, the light
/// and any surface layer are grey (the same arithmetic per channel: bit-identical, a third of
/// the work).
std::unique_ptr<SlabCompositor> scalarSlabCompositor(int channels);

/// The SIMD backend for this CPU (Highway's AVX-512 or AVX2 target, the best the CPU has,
/// chosen at run time), carrying @a channels like scalarSlabCompositor; null where the CPU has
/// no AVX2 and FMA.
std::unique_ptr<SlabCompositor> simdSlabCompositor(int channels);

/// The instruction set simdSlabCompositor uses: Highway's name for it ("AVX3" for AVX-512,
/// "AVX2"; "EMU128" or "SCALAR" where there is no SIMD backend).
const char* simdTarget();

} // namespace detail
} // namespace vdb_ewa
