/// @file frame_parts.h
/// @brief What the whole frame and the streamed frame share (renderer.cpp, streamed_frame.cpp):
///        the stage timer, the memory budget, the light maps, and the stats and warning lines
///        they fill from the stages' counters.
#pragma once

#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_stats.h>

#include "shading/shading.h"
#include "source/source.h"
#include "support/memory_budget.h"
#include "support/progress.h"

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

struct RasterStats;

/// Seconds between laps, for RenderStats' stage timings.
class StageTimer
{
public:
    double lap()
    {
        const auto now = std::chrono::steady_clock::now();
        const double s = std::chrono::duration<double>(now - mStart).count();
        mStart = now;
        return s;
    }

private:
    std::chrono::steady_clock::time_point mStart = std::chrono::steady_clock::now();
};

/// The frame's memory budget, naming the grid in its errors.
MemoryBudget budgetFor(const GridSource::Impl& grid, const RenderSettings& settings);

/// "@a n @a what": a warning line.
std::string countLine(std::uint64_t n, const std::string& what);

/// How many sub-frames a frame averages (Renderer::renderSubFrames): the motion samples where
/// the grid @a moving over the shutter, the lens samples through a @a lens; one for a @a deep image.
int subFrameCount(const RenderSettings& settings, bool moving, bool lens, bool deep);

/// A part of a frame's render (a sub-frame, a channel) added to @a stats: the counts and times
/// add up; the warnings and the rest are the part's (@a first: it replaces them).
void addPartStats(RenderStats& stats, RenderStats&& part, bool first);

/// The frame of media whose extinctions differ in hue, rendered once per channel with every
/// medium grey at that channel's coefficients (detail::mixMaterials' channel): channel c of
/// the colour, the transmittance and the passes from @a channels[c]; alpha, 1 - the mean of
/// the channels' transmittances, the mean of their alphas; Z the nearest.
Frame assembleChannels(Frame (&channels)[3]);

/// Sub-frame @a s of @a n's settings: one sample each, and (@a moving) the shutter's part
/// [open + s d, open + (s + 1) d], d = (close - open) / n.
RenderSettings subFrameSettings(const RenderSettings& settings, bool moving, int s, int n);

/// Sub-frame @a s of @a n added to @a average (the first replaces it): colour and alpha
/// (premultiplied), transmittance and the passes weighted 1/n; Z, where alpha reaches 0.5, is
/// the nearest sub-frame's.
void addToAverage(Frame& average, Frame&& sub, int s, int n);

/// The volume rasteriser's counters in the frame's stats.
void addRasterStats(const RasterStats& raster, RenderStats& stats);

/// The voxel values the kernels skipped or clamped, a line each.
void valueWarnings(std::uint64_t notANumber, std::uint64_t clamped, std::vector<std::string>& warnings);

/// What the projection clamped or left out, a line each.
void splatWarnings(std::uint64_t beforeNear, std::uint64_t clampedNear, std::uint64_t clampedGrazing, std::uint64_t clippedSpan,
    std::vector<std::string>& warnings);

/// Motion blur's counters, added to @a stats.
void addMotionStats(const MotionStats& motion, RenderStats& stats);

/// What motion blur clamped or stretched, a line each (@a splitSigmas: MotionBlur::splitSigmas).
void motionWarnings(const MotionStats& motion, double splitSigmas, std::vector<std::string>& warnings);

/// A whole frame marches its light maps whole unless one would hold more lattice points than
/// this many a pixel: then it marches what its lookups read (light on demand), as the streamed
/// frame does. A file of tiles 32,768 voxels wide at 160x90 and `final` held 2e8 points for
/// 14,400 pixels (14.8 s of a 15.6 s frame); pig at `high` and 1080p 82 a pixel, marched
/// whole, where blocks of 16 x 16 rays march 1.1-1.3x faster than tiles of 4
/// (docs/performance.md#light-rays-marched-against-looked-up).
constexpr double kLightPointsPerPixelMarchedWhole = 1024.0;

/// Each light map's share of the lights' quarter of @a budget (4 bytes a lattice point): the
/// directional and point lights that scatter share it evenly.
double lightMapPoints(const RenderSettings& settings, const MemoryBudget& budget);

/// Whether a light map of @a g would hold more than kLightPointsPerPixelMarchedWhole lattice
/// points a pixel of a frame of @a pixels.
bool lightMapsOutgrowFrame(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget, double pixels);

/// Each light's light map. They take at most a quarter of the budget (4 bytes a lattice point),
/// shared between the lights; a warning where that coarsened them. Marched whole, or
/// @a onDemand (the streamed frame marches what its windows need).
std::vector<LightMap> lightMaps(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, std::vector<std::string>& warnings, bool onDemand = false);

/// The point and spot lights' maps, sharing the lights' quarter of the budget with the
/// directional lights' (lightMaps); a warning where that coarsened them. Marched whole.
PointLights pointLightMaps(const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, std::vector<std::string>& warnings);

/// Every splat's optical depth and source terms will be the same in R, G and B (the raster's
/// one-channel path), known from the settings before any splat exists: a grey medium and
/// lights, no material colours.
bool greyFrame(const RenderSettings& settings, const GridSource::Impl& g);

} // namespace detail
} // namespace vdb_ewa
