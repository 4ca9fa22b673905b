/// @file camera_file_option.h
/// @brief --camera-file: a camera from a JSON file or from an EXR's header (docs/output.md#cameras-from-files).
#pragma once

#include <vdb_ewa/camera.h>

#include <string>

namespace vdb_ewa::cli {

/// The camera in @a path at frame @a frame: an .exr's (readExrCamera), or a .json file's, which
/// holds either vdb_render's camera options as keys ("res", "camera", "translate", "rotate" or
/// "lookat" and "up", "fov" or "focal", "aperture", "frame", "near", "far"), or a
/// "worldToCamera" matrix (4 rows of 4, OpenEXR's convention) with "fov" or
/// "screenWindowWidth", or "keys": keyframes, each such an object with its frame "at",
/// interpolated linearly at @a frame (held before the first and after the last).
/// @throw IoError naming the file if it cannot be read; ValueError naming the key.
CameraSettings readCameraFile(const std::string& path, int frame);

} // namespace vdb_ewa::cli
