/// @file blank_frame.h
/// @brief A frame before compositing: the beauty and every requested flat pass, each at its
///        empty-pixel value (colour 0, transmittance 1, Z +inf). Deep images are assembled
///        separately.
#pragma once

#include <vdb_ewa/frame.h>

#include "support/huge_page_allocator.h"

#include <limits>

namespace vdb_ewa {
namespace detail {

inline Frame blankFrame(int width, int height, const PassRequest& passes)
{
    // Each plane advised as huge pages before its first touch: at 1080p the planes are 33-50 MB,
    // 0.15 s of page faults in 4 KiB pages here (docs/performance.md#fixed-costs).
    Frame frame;
    frame.beauty.width = width;
    frame.beauty.height = height;
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    assignAdvised(frame.beauty.rgba, pixels * 4, 0.0f);
    if (passes.depth) assignAdvised(frame.depth, pixels, std::numeric_limits<float>::infinity());
    if (passes.transmittance) assignAdvised(frame.transmittance, pixels * 3, 1.0f);
    if (passes.shadow) assignAdvised(frame.shadow, pixels * 3, 0.0f);
    if (passes.emission) assignAdvised(frame.emission, pixels * 3, 0.0f);
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
