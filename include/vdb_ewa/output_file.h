/// @file output_file.h
/// @brief Output paths: checked before rendering, written through a temporary file.
#pragma once

#include <string>

#include "types.h"

namespace vdb_ewa {

/// Check, before rendering, that @a path can be written: its folder exists and is writable,
/// and it is not a folder or a read-only file. @throw IoError naming the path and the problem.
VDB_EWA_API void checkOutputWritable(const std::string& path);

} // namespace vdb_ewa
