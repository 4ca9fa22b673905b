/// @file openvdb_grid.h
/// @brief Render a grid a host application (Houdini, Blender...) already holds in memory.
/// @note This is the one public header that includes OpenVDB; include it only where the
///       host's OpenVDB is the one vdb_ewa was built against.
#pragma once

#include <openvdb/Grid.h>

#include "grid_source.h"

namespace vdb_ewa {

/// Wrap a float or double grid without a file round trip (a double grid is converted to
/// float). @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource gridSourceFromOpenVDB(openvdb::GridBase::ConstPtr grid);

/// @a source with material colours from a host's vec3s grid (see GridSource::withColorGrid).
/// @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource withColorGrid(const GridSource& source, openvdb::GridBase::ConstPtr colorGrid);

} // namespace vdb_ewa
