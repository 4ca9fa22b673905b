/// @file image_codec_module.cpp
/// @brief libvdb_ewa_images.so: reads and writes images through OpenImageIO for vdb_ewa
///        (image_codec.h says why this is a module of its own). Nothing here throws across the
///        seam but the caller's own @a accept.
#include "output/image_codec.h"

#include <OpenImageIO/imageio.h>

#include <memory>

namespace {

using vdb_ewa::detail::CodecPixels;

/// OpenImageIO's error text on one line of at most 160 characters.
std::string oneLine(std::string text)
{
    for (char& ch : text) {
        if (ch == '\n' || ch == '\r' || ch == '\t') ch = ' ';
    }
    return text.size() > 160 ? text.substr(0, 157) + "..." : text;
}

std::string write(const std::string& path, const char* format, const CodecPixels& pixels,
    const std::vector<std::pair<std::string, std::string>>& attributes)
{
    const bool bytes = !pixels.bytes.empty();
    const OIIO::TypeDesc type = bytes ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT;
    OIIO::ImageSpec spec(pixels.width, pixels.height, pixels.channels, type);
    for (const auto& [key, value] : attributes) spec.attribute(key, value);
    // By format name: the caller's temporary file has no extension to go by.
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(format);
    if (!out) return std::string("OpenImageIO has no ") + format + " writer (" + oneLine(OIIO::geterror()) + ")";
    const void* data = bytes ? static_cast<const void*>(pixels.bytes.data()) : static_cast<const void*>(pixels.floats.data());
    if (!(out->open(path, spec) && out->write_image(type, data) && out->close())) {
        return std::string("cannot write ") + format + " (" + oneLine(out->geterror()) + ")";
    }
    return {};
}

std::string read(const std::string& path, CodecPixels& pixels, const std::function<void(int, int, int)>& accept)
{
    auto in = OIIO::ImageInput::open(path);
    if (!in) return "cannot be read as an image (" + oneLine(OIIO::geterror()) + ")";
    const OIIO::ImageSpec& spec = in->spec();
    accept(spec.width, spec.height, spec.nchannels);
    pixels.width = spec.width;
    pixels.height = spec.height;
    pixels.channels = spec.nchannels;
    pixels.floats.resize(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(spec.nchannels));
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.floats.data())) {
        return "cannot read its pixels (" + oneLine(in->geterror()) + ")";
    }
    return {};
}

constexpr vdb_ewa::detail::ImageCodec kCodec{&write, &read};

} // namespace

extern "C" __attribute__((visibility("default"))) const vdb_ewa::detail::ImageCodec* VDB_EWA_IMAGE_CODEC_ENTRY()
{
    return &kCodec;
}
