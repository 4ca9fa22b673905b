/// @file preview_output.cpp
#include <vdb_ewa/preview_output.h>

#include "output/atomic_write.h"

#include <vdb_ewa/error.h>

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vdb_ewa {

void writePreviewPng(const Image& beauty, const ColorTransform& toDisplay, const std::string& path)
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
    detail::writeAtomically(path, "PNG", [&](const std::string& tmp) {
        png_image image{};
        image.version = PNG_IMAGE_VERSION;
        image.width = png_uint_32(beauty.width);
        image.height = png_uint_32(beauty.height);
        image.format = PNG_FORMAT_RGB;
        if (!png_image_write_to_file(&image, tmp.c_str(), 0, bytes.data(), 0, nullptr)) {
            const std::string message = image.message;
            png_image_free(&image);
            throw IoError(path + ": cannot write PNG (" + message + ")");
        }
    });
}

} // namespace vdb_ewa
