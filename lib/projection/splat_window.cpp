/// @file splat_window.cpp
#include "projection/splat_window.h"

#include <algorithm>
#include <vector>

namespace vdb_ewa {
namespace detail {
namespace {

/// Append the splats @a which (indices into @a from, in order), their shares, moments, pass
/// sources and shifts, to @a to: sized once, then copied.
void appendSome(SplatSet& to, const SplatSet& from, const std::vector<std::size_t>& which)
{
    const std::size_t passFloats = std::size_t(from.passSourceCount) * 3; // the same in both
    std::size_t shares = to.shares.size();
    for (const std::size_t i : which) shares += from.splats[i].slabCount;
    std::size_t splat = to.splats.size(), share = to.shares.size();
    to.splats.resize(splat + which.size());
    to.passSources.resize(to.splats.size() * passFloats);
    // Shifts where either set has them (zero for the splats of a set without: they stood still).
    const bool shifted = !to.shifts.empty() || !from.shifts.empty();
    if (shifted) to.shifts.resize(3 * to.splats.size());
    to.shares.resize(shares);
    to.shareMoments.resize(2 * shares);
    for (const std::size_t i : which) {
        const Splat& s = from.splats[i];
        std::copy_n(from.shares.data() + s.shareOffset, s.slabCount, to.shares.data() + share);
        std::copy_n(from.shareMoments.data() + 2 * s.shareOffset, 2 * std::size_t(s.slabCount), to.shareMoments.data() + 2 * share);
        std::copy_n(from.passSources.data() + i * passFloats, passFloats, to.passSources.data() + splat * passFloats);
        if (!from.shifts.empty()) std::copy_n(from.shifts.data() + 3 * i, 3, to.shifts.data() + 3 * splat);
        to.splats[splat] = s;
        to.splats[splat++].shareOffset = share;
        share += s.slabCount;
    }
}

} // namespace

void appendSplats(SplatSet& to, const SplatSet& from)
{
    if (from.splats.empty()) return;
    if (to.splats.empty()) {
        to.slabs = from.slabs;
        to.passSourceCount = from.passSourceCount;
    }
    std::vector<std::size_t> all(from.splats.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
    appendSome(to, from, all);
}

SplatSet splitSplatsAt(SplatSet& set, std::int64_t slab)
{
    SplatSet behind;
    behind.slabs = set.slabs;
    behind.passSourceCount = set.passSourceCount;
    std::vector<std::size_t> moved;
    for (std::size_t i = 0; i < set.splats.size(); ++i) {
        if (set.splats[i].firstSlab >= slab) moved.push_back(i);
    }
    if (moved.empty()) return behind;
    appendSome(behind, set, moved);
    // The rest compacted in place; their shares stay where they are (shareOffset still points
    // at them).
    const std::size_t passFloats = std::size_t(set.passSourceCount) * 3;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < set.splats.size(); ++i) {
        if (set.splats[i].firstSlab >= slab) continue;
        if (kept != i) {
            set.splats[kept] = set.splats[i];
            std::copy_n(set.passSources.begin() + std::ptrdiff_t(i * passFloats), passFloats, set.passSources.begin() + std::ptrdiff_t(kept * passFloats));
            if (!set.shifts.empty()) std::copy_n(set.shifts.begin() + std::ptrdiff_t(3 * i), 3, set.shifts.begin() + std::ptrdiff_t(3 * kept));
        }
        ++kept;
    }
    set.splats.resize(kept);
    set.passSources.resize(kept * passFloats);
    if (!set.shifts.empty()) set.shifts.resize(3 * kept);
    return behind;
}

} // namespace detail
} // namespace vdb_ewa
