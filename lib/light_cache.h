/// @file light_cache.h
/// @brief The light maps a Scene keeps between renders (docs/api.md#what-a-scene-reuses). A
///        light map depends on the grid, the lights and the medium, never on the camera: a
///        render hands its maps, with every ray it marched, to the next render whose grid and
///        light settings are the same (LightKey). A ray's samples do not depend on which other
///        rays are marched, or when, so a kept map looks up what a fresh one would: the image is
///        the cold render's bit for bit.
#pragma once

#include "frame_parts.h"

#include <memory>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// What a light map and the point lights' maps read of the settings, as numbers: two renders
/// whose keys are equal make the same maps (light_cache.cpp lists them).
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
    /// (pointLightMaps) for @a settings: the kept ones where their key is this render's, made
    /// anew otherwise. Their warnings are added to @a warnings either way, and each map's
    /// counters start at this render (LightMap::beginRender). @a reused: maps handed over.
    const std::vector<LightMap>& lightMaps(const RenderSettings& settings, const MemoryBudget& budget, Progress& progress,
        std::vector<std::string>& warnings, std::uint64_t& reused);
    const PointLights& pointLightMaps(const RenderSettings& settings, const MemoryBudget& budget, Progress& progress,
        std::vector<std::string>& warnings, std::uint64_t& reused);

    /// Let go of every map: after a render that threw (a cancelled one may have left a tile of
    /// rays half marched), and when a Scene is cleared.
    void clear();

private:
    const GridSource::Impl* mGrid;
    LightKey mKey, mPointKey;
    std::unique_ptr<std::vector<LightMap>> mMaps;
    std::unique_ptr<PointLights> mPoints;
    std::vector<std::string> mWarnings, mPointWarnings;
};

} // namespace detail
} // namespace vdb_ewa
