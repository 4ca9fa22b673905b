/// @file preview_output.h
/// @brief An 8-bit display-referred PNG preview of a beauty image (--preview).
#pragma once

#include <string>

#include "color_management.h"
#include "image.h"

namespace vdb_ewa {

/// Write @a beauty over black (its premultiplied colour) through @a toDisplay (e.g. the
/// config's sRGB display and view), clamped to [0, 1] and rounded to 8-bit RGB, to a PNG,
/// through a temporary file renamed over @a path. @throw IoError naming the path.
VDB_EWA_API void writePreviewPng(const Image& beauty, const ColorTransform& toDisplay, const std::string& path);

} // namespace vdb_ewa
