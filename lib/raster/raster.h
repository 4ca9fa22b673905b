/// @file raster.h
/// @brief Raster stage: splats -> a Frame, tile by tile: volume splats composited in
///        image-aligned slabs and lit per slab sample; surface splats covering pixels with their
///        discs, with a z-buffer tolerance.
///        The stage's door: other stages and the renderer include this header only
///        (docs/architecture.md).
#pragma once

#include "raster/light_on_demand.h"
#include "raster/slab_compositor.h"
#include "raster/surface_rasterizer.h"
#include "raster/streamed_raster.h"
#include "raster/tile_bins.h"
#include "raster/tile_rasterizer.h"
