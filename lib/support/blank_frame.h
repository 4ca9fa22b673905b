/// @file blank_frame.h
/// @brief A frame before compositing: the beauty and every requested flat pass, each at its
///        empty-pixel value (colour 0, transmittance 1, Z +inf). Deep images are assembled
///        separately.
#pragma once

#include <vdb_ewa/frame.h>

#include <limits>

namespace vdb_ewa {
namespace detail {

inline Frame blankFrame(int width, int height, const PassRequest& passes)
{
    Frame frame;
    frame.beauty = Image(width, height);
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    if (passes.depth) frame.depth.assign(pixels, std::numeric_limits<float>::infinity());
    if (passes.transmittance) frame.transmittance.assign(pixels * 3, 1.0f);
    if (passes.shadow) frame.shadow.assign(pixels * 3, 0.0f);
    if (passes.emission) frame.emission.assign(pixels * 3, 0.0f);
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
