/// @file shading.h
/// @brief Shading stage: the one optical model (medium, light) every integrator calls, and the
///        light's transmittance (the light map for the splatter, shadow rays for the references).
///        The stage's door: other stages and the renderer include this header only
///        (docs/architecture.md).
#pragma once

#include "shading/blackbody.h"
#include "shading/grid_emission.h"
#include "shading/light_map.h"
#include "shading/material_mix.h"
#include "shading/optical_model.h"
#include "shading/phase_function.h"
#include "shading/scattering_octaves.h"
#include "shading/point_light_map.h"
#include "shading/shadow_transmittance.h"
