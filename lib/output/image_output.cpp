/// @file image_output.cpp
/// @brief Images other than EXR through OpenImageIO (its module, image_codec.h): 8-bit
///        display-referred dailies and .hdr.
#include <vdb_ewa/image_output.h>

#include "output/atomic_write.h"
#include "output/image_codec.h"

#include <vdb_ewa/error.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>

namespace vdb_ewa {
namespace {

struct FormatInfo
{
    ImageFormat format;
    const char* extensions[2]; ///< the usual one first
    const char* writer;        ///< OpenImageIO's format name
};

constexpr FormatInfo kFormats[] = {
    {ImageFormat::Exr, {".exr", nullptr}, "openexr"},
    {ImageFormat::Png, {".png", nullptr}, "png"},
    {ImageFormat::Jpeg, {".jpg", ".jpeg"}, "jpeg"},
    {ImageFormat::Tiff, {".tif", ".tiff"}, "tiff"},
    {ImageFormat::Ppm, {".ppm", nullptr}, "pnm"},
    {ImageFormat::Hdr, {".hdr", nullptr}, "hdr"},
};

const FormatInfo& infoOf(ImageFormat format)
{
    return *std::find_if(std::begin(kFormats), std::end(kFormats), [&](const FormatInfo& f) { return f.format == format; });
}

/// @a beauty's colour over black as 8-bit RGB through @a toDisplay.
std::vector<std::uint8_t> displayBytes(const Image& beauty, const ColorTransform& toDisplay)
{
    const std::size_t pixels = std::size_t(beauty.width) * std::size_t(beauty.height);
    std::vector<float> rgb(pixels * 3);
    for (std::size_t i = 0; i < pixels; ++i) std::copy_n(&beauty.rgba[4 * i], 3, &rgb[3 * i]);
    toDisplay.apply(rgb.data(), pixels, 3);
    std::vector<std::uint8_t> bytes(pixels * 3);
    for (std::size_t i = 0; i < rgb.size(); ++i) {
        const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
        bytes[i] = std::uint8_t(std::lround(v * 255.0f));
    }
    return bytes;
}

/// @a beauty's colour over black as float RGB, >= 0 and finite (what RGBE can hold).
std::vector<float> radianceFloats(const Image& beauty)
{
    const std::size_t pixels = std::size_t(beauty.width) * std::size_t(beauty.height);
    std::vector<float> rgb(pixels * 3);
    for (std::size_t i = 0; i < pixels; ++i)
        for (std::size_t c = 0; c < 3; ++c) {
            const float v = beauty.rgba[4 * i + c];
            rgb[3 * i + c] = std::isfinite(v) ? std::max(v, 0.0f) : 0.0f;
        }
    return rgb;
}

void writeAs(ImageFormat format, const Image& beauty, const std::string& path, const ColorTransform* toDisplay,
    const ImageFileOptions& options)
{
    const FormatInfo& info = infoOf(format);
    if (format == ImageFormat::Exr) throw ValueError(path + ": EXR files are written by writeExr");
    const bool display = isDisplayReferred(format);
    if (display != (toDisplay != nullptr)) {
        throw ValueError(path + (display ? ": an 8-bit image needs a display transform" : ": .hdr holds scene-referred values: no display transform"));
    }
    std::vector<std::pair<std::string, std::string>> attributes = options.attributes;
    if (!options.colorSpace.empty()) {
        std::string lower = options.colorSpace.substr(0, 4);
        std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
        attributes.emplace_back("oiio:ColorSpace", lower == "srgb" ? std::string("sRGB") : options.colorSpace);
    }
    detail::CodecPixels pixels{beauty.width, beauty.height, 3, {}, {}};
    if (display) pixels.bytes = displayBytes(beauty, *toDisplay);
    else pixels.floats = radianceFloats(beauty);
    const detail::ImageCodec& codec = detail::imageCodec();
    detail::writeAtomically(path, info.writer, [&](const std::string& tmp) {
        const std::string error = codec.write(tmp, info.writer, pixels, attributes);
        if (!error.empty()) throw IoError(path + ": " + error);
    });
}

} // namespace

std::optional<ImageFormat> imageFormatOf(const std::string& path)
{
    std::string lower = path;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    for (const FormatInfo& f : kFormats)
        for (const char* ext : f.extensions) {
            const std::string e = ext ? ext : "";
            if (!e.empty() && lower.size() > e.size() && lower.compare(lower.size() - e.size(), e.size(), e) == 0) return f.format;
        }
    return std::nullopt;
}

std::string imageFormatExtensions()
{
    std::string out;
    const std::size_t n = std::size(kFormats);
    for (std::size_t i = 0; i < n; ++i) out += (i == 0 ? "" : i + 1 == n ? " or " : ", ") + std::string(kFormats[i].extensions[0]);
    return out;
}

bool isDisplayReferred(ImageFormat format)
{
    return format != ImageFormat::Exr && format != ImageFormat::Hdr;
}

void writeImage(const Image& beauty, const std::string& path, const ColorTransform* toDisplay, const ImageFileOptions& options)
{
    const std::optional<ImageFormat> format = imageFormatOf(path);
    if (!format) throw ValueError(path + ": unknown image format (expected " + imageFormatExtensions() + ")");
    writeAs(*format, beauty, path, toDisplay, options);
}

void loadImageModule()
{
    detail::imageCodec();
}

void writePreviewPng(const Image& beauty, const ColorTransform& toDisplay, const std::string& path)
{
    writeAs(ImageFormat::Png, beauty, path, &toDisplay, {});
}

} // namespace vdb_ewa
