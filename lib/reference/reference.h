/// @file reference.h
/// @brief Reference stage: ray-marching integrators (the trilinear field with a shadow ray per
///        sample, as vdb_render; and the splatter's own Gaussian field, a diagnostic), with motion
///        blur's moved voxels.
///        The stage's door: other stages and the renderer include this header only
///        (docs/architecture.md).
#pragma once

#include "reference/moved_voxels.h"
#include "reference/path_tracer.h"
#include "reference/reference_integrator.h"
