/// @file exr_output.h
/// @brief Image -> OpenEXR file (float R, G, B, A, premultiplied). No Imf types here.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "image.h"

namespace vdb_ewa {

/// Check, before rendering, that @a path can be written: its folder exists and is writable.
/// @throw IoError naming the path and the problem.
VDB_EWA_API void checkOutputWritable(const std::string& path);

/// Write @a image to @a path, through a temporary file in the same folder renamed over the
/// destination, so a failure never leaves a damaged file. @a attributes become string
/// attributes of the header. @throw IoError naming the path and the problem.
VDB_EWA_API void writeExr(const Image& image, const std::string& path,
    const std::vector<std::pair<std::string, std::string>>& attributes = {});

/// Let OpenEXR compress with @a threads threads (0 = all cores). Process-wide (OpenEXR's
/// global thread pool): for applications such as the CLI, not for plugins inside a host.
VDB_EWA_API void setExrThreadsProcessWide(int threads);

/// Read an RGBA EXR written by us or by vdb_render (for tests and benchmarks).
/// @throw IoError naming the path.
VDB_EWA_API Image readExr(const std::string& path);

} // namespace vdb_ewa
