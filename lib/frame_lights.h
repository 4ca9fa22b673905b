/// @file frame_lights.h
/// @brief A frame's light maps: made for it alone, or kept by a Scene between its renders
///        (LightCache; docs/api.md#scenes-what-a-render-reuses). A light map depends on the
///        grid, the lights and the medium, never on the camera: a render hands its maps, with
///        every ray it marched, to the next render whose grid and light settings are the same
///        (LightKey). A ray's samples do not depend on which other rays are marched, or when, so
///        a kept map looks up what a fresh one would: the image is the cold render's bit for bit.
#pragma once

#include "frame_parts.h"

#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// What a light map and the point lights' maps read of the settings, as numbers: two renders
/// whose keys are equal make the same maps (frame_lights.cpp lists them).
using LightKey = std::vector<double>;
LightKey lightKey(const RenderSettings& settings, const MemoryBudget& budget);

class LightCache
{
public:
    /// Maps for renders of @a grid only (a Scene's grid); any other grid is not served.
    explicit LightCache(const GridSource::Impl* grid) : mGrid(grid) {}

    /// Whether renders of @a g may take their maps from here.
    bool serves(const GridSource::Impl& g) const { return &g == mGrid; }

    /// The directional lights' maps (lightMaps, marched on demand) and the point lights'
    /// (pointLightMaps) for @a settings, in maps() and points(): the kept ones where their key
    /// is this render's, all made anew otherwise (the directional maps' share of the budget
    /// depends on the point lights too). Their warnings are added to @a warnings either way, and
    /// each map's counters start at this render (LightMap::beginRender).
    /// @return whether the maps were kept from an earlier render.
    bool prepare(const RenderSettings& settings, const MemoryBudget& budget, Progress& progress, std::vector<std::string>& warnings);
    const std::vector<LightMap>& maps() const { return mMaps; }
    const PointLights& points() const { return mPoints; }

    /// Let go of every map: after a render that threw (a cancelled one may have left a tile of
    /// rays half marched), and when a Scene is cleared.
    void clear();

private:
    const GridSource::Impl* mGrid;
    LightKey mKey; ///< of the maps held; empty: none
    std::vector<LightMap> mMaps;
    PointLights mPoints;
    std::vector<std::string> mWarnings; ///< those their making gave
};

/// A frame's light maps: a Scene's kept ones (LightCache), or made for this frame alone.
struct FrameLights
{
    const std::vector<LightMap>* maps = nullptr;
    const PointLights* points = nullptr;
    bool kept = false; ///< the maps were made by an earlier render (a Scene's)
    std::vector<LightMap> ownMaps;
    PointLights ownPoints;
};
/// Fills @a lights from @a cache where it serves @a g (a Scene's grid), else with maps of its
/// own (lightMaps, pointLightMaps). Maps of its own are marched whole unless @a onDemand; kept
/// ones are marched on demand, and whole here unless @a onDemand (an --iso surface reads them
/// without asking). Their warnings, and how many maps were kept (lightMapsReused), go into
/// @a stats.
void frameLights(FrameLights& lights, const RenderSettings& settings, const GridSource::Impl& g, const MemoryBudget& budget,
    Progress& progress, RenderStats& stats, bool onDemand, LightCache* cache);

/// The light maps' rays in all, marched by this render and by earlier ones (a Scene's kept
/// maps), into @a stats (the point lights' are marched whole), and the time spent marching
/// light on demand, moved from the rasteriser's stage to the shadows' (call it after the
/// rasteriser's time is in @a stats).
void addLightStats(const FrameLights& lights, RenderStats& stats);

} // namespace detail
} // namespace vdb_ewa
