/// @file splat_window.h
/// @brief A streamed frame's splats between windows: the splats a window made that start
///        behind its end wait for the next window (docs/architecture.md#the-streamed-frame).
#pragma once

#include "projection/splat_projection.h"

#include <cstdint>

namespace vdb_ewa {
namespace detail {

/// Append @a from's splats, with their slab shares, moments and pass sources, after @a to's
/// (@a to takes @a from's slabs and pass layout if it has no splats).
void appendSplats(SplatSet& to, const SplatSet& from);

/// Move the splats of @a set whose first slab is @a slab or behind into the set returned; both
/// keep their order (@a set its shares array, some of it no longer used). Counters stay with
/// @a set.
SplatSet splitSplatsAt(SplatSet& set, std::int64_t slab);

} // namespace detail
} // namespace vdb_ewa
