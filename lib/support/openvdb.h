/// @file openvdb.h
/// @brief The one way the library includes OpenVDB: with default symbol visibility.
/// @note The library is compiled with -fvisibility=hidden, but OpenVDB's headers must keep the
///       visibility libopenvdb.so itself was built with (default). Its templates share
///       vague-linkage statics between every module that instantiates them, e.g.
///       Tree<...>::treeType() fills the static Tree::sTreeTypeName once, through
///       std::call_once. Compiled hidden, our copies of those statics become private while the
///       std:: helpers that run the call_once lambda (libstdc++'s namespace std is always
///       default visibility) stay exported from the executable and interpose libopenvdb's own:
///       openvdb::initialize() then fills the executable's hidden sTreeTypeName, reads its own
///       (still null) and crashes. With default visibility the statics are unique across
///       modules again (as in a default build); the installed shared library still exports
///       none of them (lib/vdb_ewa.map). Include every OpenVDB header through this file or
///       openvdb_tools.h (a ctest checks it).
#pragma once

#pragma GCC visibility push(default)
#include <openvdb/openvdb.h>

/// The Grid and Tree classes of the grids the library and its tests make, declared here and
/// instantiated once, in support/openvdb_instances.cpp. A unit that makes such a grid otherwise
/// compiles all their virtual members (I/O, topology, statistics) again: about half of its build
/// time (CONTRIBUTING.md#build-time). Their inline members are still instantiated where used.
/// Only targets that link those instances define VDB_EWA_OPENVDB_INSTANCES (the library's objects
/// and the tests; not the Python module, which links the shared library, whose version script
/// hides them).
#define VDB_EWA_OPENVDB_GRID_CLASSES(Declare, TreeType)                                              \
    Declare template class openvdb::tree::Tree<TreeType::RootNodeType>;                            \
    Declare template class openvdb::Grid<TreeType>;
#define VDB_EWA_OPENVDB_INSTANCES_OF(Declare)                                                      \
    VDB_EWA_OPENVDB_GRID_CLASSES(Declare, openvdb::FloatTree)                                      \
    VDB_EWA_OPENVDB_GRID_CLASSES(Declare, openvdb::Vec3STree)                                      \
    VDB_EWA_OPENVDB_GRID_CLASSES(Declare, openvdb::MaskTree)
#ifdef VDB_EWA_OPENVDB_INSTANCES
VDB_EWA_OPENVDB_INSTANCES_OF(extern)
#endif
#pragma GCC visibility pop
