/// @file openvdb_grid.h
/// @brief Render a grid a host application (Houdini, Blender...) already holds in memory.
/// @note This is the one public header that includes OpenVDB; include it only where the
///       host's OpenVDB is the one vdb_ewa was built against.
#pragma once

// OpenVDB declarations keep the default visibility libopenvdb was built with, also in code
// compiled with -fvisibility=hidden: its templates share statics across modules (hidden copies
// crash openvdb::initialize(); lib/support/openvdb.h explains).
#pragma GCC visibility push(default)
#include <openvdb/Grid.h>
#pragma GCC visibility pop

#include "grid_source.h"

namespace vdb_ewa {

/// Wrap a float or double grid without a file round trip (a double grid is converted to
/// float). @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource gridSourceFromOpenVDB(openvdb::GridBase::ConstPtr grid);

/// @a source with material colours from a host's vec3s grid (see GridSource::withColorGrid).
/// @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource withColorGrid(const GridSource& source, openvdb::GridBase::ConstPtr colorGrid);

/// @a source with emission from a host's float or double grid (see GridSource::withEmissionGrid).
/// @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource withEmissionGrid(const GridSource& source, openvdb::GridBase::ConstPtr emissionGrid);

/// @a source with blackbody emission from a host's temperature grid (see
/// GridSource::withTemperatureGrid). @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource withTemperatureGrid(const GridSource& source, openvdb::GridBase::ConstPtr temperatureGrid);

/// @a source with motion blur from a host's vec3s or vec3d velocity grid (see
/// GridSource::withVelocityGrid). @throw InputError for a null grid or another value type.
VDB_EWA_API GridSource withVelocityGrid(const GridSource& source, openvdb::GridBase::ConstPtr velocityGrid);

} // namespace vdb_ewa
