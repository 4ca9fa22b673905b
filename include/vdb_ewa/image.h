/// @file image.h
/// @brief A float RGBA image in memory; no I/O.
/// @note Colour is premultiplied by alpha; row 0 is the top of the image.
#pragma once

#include <cstddef>
#include <vector>

#include "types.h"

namespace vdb_ewa {

struct VDB_EWA_API Image
{
    int width = 0;
    int height = 0;
    std::vector<float> rgba; ///< width * height * 4 floats, row-major, premultiplied

    Image() = default;
    Image(int w, int h) : width(w), height(h), rgba(std::size_t(w) * std::size_t(h) * 4, 0.0f) {}

    float* pixel(int x, int y) { return &rgba[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4]; }
    const float* pixel(int x, int y) const
    {
        return &rgba[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4];
    }
    /// True if every channel of every pixel is finite.
    bool allFinite() const;
};

} // namespace vdb_ewa
