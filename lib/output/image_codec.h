/// @file image_codec.h
/// @brief The seam between vdb_ewa and OpenImageIO, which reads and writes every image format
///        but EXR (docs/output.md#image-formats). OpenImageIO links about 240 libraries (ffmpeg,
///        GDAL, OpenCV, DCMTK...): loading them made every process start 0.3 s slower than
///        vdb_render's (docs/performance.md#fixed-costs). So the code that calls OpenImageIO
///        is a module of its own, libvdb_ewa_images.so (image_codec_module.cpp), opened on the
///        first image that is not an EXR; a render that writes an EXR never loads it.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// Interleaved pixels: 8-bit values in @a bytes, or floats in @a floats.
struct CodecPixels
{
    int width = 0, height = 0, channels = 0;
    std::vector<std::uint8_t> bytes;
    std::vector<float> floats;
};

/// What the module gives. Both sides are built together, so C++ types cross; errors cross as
/// text (an empty string: success), since the module has none of vdb_ewa's exception types.
struct ImageCodec
{
    /// Write @a pixels (its bytes if any, else its floats) to @a path through OpenImageIO's
    /// writer @a format ("png", "hdr"...), with string metadata @a attributes. An error reads
    /// "cannot write FORMAT (why)".
    std::string (*write)(const std::string& path, const char* format, const CodecPixels& pixels,
        const std::vector<std::pair<std::string, std::string>>& attributes);
    /// Read the first subimage of @a path as floats into @a pixels. @a accept sees its width,
    /// height and channel count before any pixel is read, and throws to refuse it. An error
    /// reads "cannot be read as an image (why)" or "cannot read its pixels (why)".
    std::string (*read)(const std::string& path, CodecPixels& pixels, const std::function<void(int, int, int)>& accept);
};

/// The module's entry point, exported by name from libvdb_ewa_images.so; the suffix is bumped
/// whenever ImageCodec changes, so a stale module is refused instead of called.
#define VDB_EWA_IMAGE_CODEC_ENTRY vdb_ewa_image_codec_v1

/// The module's codec, loaded on first use (thread-safe): from the folder of the binary that
/// holds this code (libvdb_ewa.so, or a program linked statically), then that folder's ../lib;
/// never through the dynamic loader's search path. Throws Error (an installation fault, the CLI's exit
/// 4) naming the module if none loads.
const ImageCodec& imageCodec();

} // namespace detail
} // namespace vdb_ewa
