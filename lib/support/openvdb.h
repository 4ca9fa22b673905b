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
#pragma GCC visibility pop
