/// @file camera_file.h
/// @brief Cameras from elsewhere (docs/output.md#cameras-from-files): the camera an EXR was
///        rendered with, read back from its header, and the exact record vdb_ewa writes there.
#pragma once

#include <string>

#include "camera.h"

namespace vdb_ewa {

/// A lossless text record of @a settings (every number to 17 significant digits), written by
/// vdb_ewa as the EXR attribute vdb_ewa/camera-record. @a settings must name its orientation (rotate,
/// or lookAt), not leave it to a grid's default target.
VDB_EWA_API std::string cameraRecord(const CameraSettings& settings);

/// The settings of a cameraRecord. @throw ValueError naming what is wrong.
VDB_EWA_API CameraSettings cameraFromRecord(const std::string& record);

/// Settings from OpenEXR's camera attributes (as vdb_ewa, Nuke and Houdini write them):
/// @a worldToCamera in OpenEXR's row-vector convention (p_camera = p_world M; camera x right,
/// y up, z forward), the eye and rotation taken from it (its axes normalised); the screen
/// window's width (the image width on the plane z = 1, or an orthographic frame's width in
/// world units) sets --focal (with vdb_ewa's default --aperture) or --frame.
/// @throw ValueError if the matrix holds no rotation (degenerate or non-finite axes).
VDB_EWA_API CameraSettings cameraFromWorldToCamera(const double worldToCamera[4][4], Projection projection,
    double screenWindowWidth, int width, int height);

/// The camera of an EXR file: the exact vdb_ewa/camera-record record where the file has one (the same
/// image, bit for bit), else OpenEXR's worldToCamera, screenWindowWidth, worldToNDC (perspective
/// or orthographic) and display window (cameraFromWorldToCamera).
/// @throw IoError naming the path if it cannot be read; ValueError if it holds no camera.
VDB_EWA_API CameraSettings readExrCamera(const std::string& path);

} // namespace vdb_ewa
