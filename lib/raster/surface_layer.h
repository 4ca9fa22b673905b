/// @file surface_layer.h
/// @brief A surface rasterised on its own (raster/surface_rasterizer.h): a level set's frame, or
///        the layer the slab compositor composites at the surface's depth (fog --iso surfaces).
#pragma once

#include "support/huge_page_allocator.h"

namespace vdb_ewa {
namespace detail {

struct SurfaceLayer
{
    int width = 0, height = 0;
    // Large arrays: a 1080p layer is 41 MB, first touched in 2 MiB pages rather than 4 KiB ones.
    LargeArray<float> rgba;  ///< premultiplied RGB and coverage alpha, 4 floats a pixel, frame order
    LargeArray<float> depth; ///< camera depth of the pixel's front layer where alpha > 0, else NaN
};

} // namespace detail
} // namespace vdb_ewa
