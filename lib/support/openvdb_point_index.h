/// @file openvdb_point_index.h
/// @brief OpenVDB's point index grid (a spatial index of points), with default symbol
///        visibility (see openvdb.h); apart from openvdb_tools.h, as only the reference's motion
///        blur needs it.
#pragma once

#include "support/openvdb.h"

#pragma GCC visibility push(default)
#include <openvdb/tools/PointIndexGrid.h>
#pragma GCC visibility pop
