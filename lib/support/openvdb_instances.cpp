/// @file openvdb_instances.cpp
/// @brief The one instantiation of OpenVDB's Grid and Tree classes for float, Vec3s and mask
///        grids, which support/openvdb.h declares extern in the library and the tests.
#include "support/openvdb.h"

#pragma GCC visibility push(default)
VDB_EWA_OPENVDB_INSTANCES_OF()
#pragma GCC visibility pop
