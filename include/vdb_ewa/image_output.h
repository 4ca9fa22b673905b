/// @file image_output.h
/// @brief Images other than EXR, written through OpenImageIO (docs/output.md#image-formats):
///        8-bit display-referred dailies (.png, .jpg, .tif, .ppm) and Radiance .hdr. No
///        OpenImageIO types here.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "color_management.h"
#include "image.h"

namespace vdb_ewa {

enum class ImageFormat { Exr, Png, Jpeg, Tiff, Ppm, Hdr };

/// The format @a path's extension names, ignoring case: .exr, .png, .jpg or .jpeg, .tif or
/// .tiff, .ppm, .hdr; none for any other.
VDB_EWA_API std::optional<ImageFormat> imageFormatOf(const std::string& path);

/// The extensions imageFormatOf knows, for messages: ".exr, .png, .jpg, .tif, .ppm or .hdr".
VDB_EWA_API std::string imageFormatExtensions();

/// True for the formats holding 8-bit display-referred pixels (.png, .jpg, .tif, .ppm); false
/// for the scene-referred float ones (.exr, .hdr).
VDB_EWA_API bool isDisplayReferred(ImageFormat format);

struct ImageFileOptions
{
    /// The pixels' colour space (OCIO's name), tagged as OpenImageIO's oiio:ColorSpace: a name
    /// beginning with "sRGB" is tagged "sRGB", OpenImageIO's own, so that PNG gets its sRGB
    /// chunk and JPEG and TIFF their Exif colour space. Empty: untagged.
    std::string colorSpace;
    /// String metadata, kept where the format holds it (PNG text chunks; JPEG, TIFF, PPM and
    /// RGBE drop it).
    std::vector<std::pair<std::string, std::string>> attributes;
};

/// Write @a beauty's premultiplied colour, over black (alpha is not written, as vdb_render's
/// .ppm and .png), to @a path in the format of its extension, which must not be .exr: an 8-bit
/// format through @a toDisplay, clamped to [0, 1] and rounded (non-finite values: 0); .hdr as
/// float RGB as given, negative and non-finite values 0 (RGBE holds neither), @a toDisplay
/// null. Through a temporary file renamed over @a path.
/// @throw ValueError for an unknown or .exr extension, or a transform that does not suit the
///        format; IoError naming the path and the problem.
VDB_EWA_API void writeImage(const Image& beauty, const std::string& path, const ColorTransform* toDisplay,
    const ImageFileOptions& options = {});

/// Write @a beauty over black through @a toDisplay (e.g. the config's sRGB display and view) as
/// an 8-bit RGB PNG, whatever @a path's extension (--preview). @throw IoError naming the path.
VDB_EWA_API void writePreviewPng(const Image& beauty, const ColorTransform& toDisplay, const std::string& path);

/// Load the module through which every format but EXR is read and written (OpenImageIO's
/// libraries take 0.3 s to load, so a process loads them on its first such image only). Call
/// it before a long render whose output needs it, so that a broken installation fails first.
/// @throw Error naming the module and why it cannot be loaded.
VDB_EWA_API void loadImageModule();

} // namespace vdb_ewa
