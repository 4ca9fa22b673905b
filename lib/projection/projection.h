/// @file projection.h
/// @brief Projection stage: kernels -> screen-space splats through the local affine approximation
///        of the perspective map (Eq. 29-33), with their slab shares (Sec. 5).
///        The stage's door: other stages and the renderer include this header only
///        (docs/architecture.md).
#pragma once

#include "projection/brick_bounds.h"
#include "projection/disc_coverage.h"
#include "projection/splat_projection.h"
#include "projection/splat_window.h"
#include "projection/surface_projection.h"
