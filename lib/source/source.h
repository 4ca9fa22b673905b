/// @file source.h
/// @brief Source stage: reads the grid and turns it into plain data for the stages after it
///        (kernels of the fog volume, with level of detail and quasi-interpolating weights;
///        material colours; flattened surface kernels of level sets).
///        The stage's door: other stages and the renderer include this header only
///        (docs/architecture.md).
#pragma once

#include "source/grid_source_impl.h"
#include "source/kernel_extraction.h"
#include "source/kernel_motion.h"
#include "source/kernel_refinement.h"
#include "source/level_of_detail.h"
#include "source/material_color.h"
#include "source/quasi_interpolation.h"
#include "source/surface_extraction.h"
