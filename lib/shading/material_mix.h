/// @file material_mix.h
/// @brief Volumes with optical models of their own (GridSource::withAddedVolume(other, medium))
///        mixed, for one render, into the one field every integrator reads: where volumes
///        interpenetrate, their extinctions and their scattered and emitted light add, each
///        weighed by its own density (docs/equations.md#volumes-with-optical-models-of-their-own).
#pragma once

#include "source/source.h"

#include <vdb_ewa/render_settings.h>

#include <memory>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The mixed volume and the settings that render it as the parts would be rendered together.
struct MixedFrame
{
    std::shared_ptr<const GridSource::Impl> grid;
    RenderSettings settings;
    std::vector<std::string> warnings;
};

/// Every medium's extinction is in proportion to the grid's (grey media, tinted albedos, one
/// hue in different strengths): one mix is exact. Else the frame is rendered once per channel
/// (@a channel of mixMaterials), or, where it cannot be (a deep image), with the others grey
/// at their means (mixMaterials warns).
bool extinctionsInProportion(const GridSource::Impl& grid, const RenderSettings& settings);

/// Mix @a grid's volumes (GridSource::Impl::addedMaterials; @a settings' medium is the grid's
/// own) into one volume whose density is the extinction-weighted sum sum_j k_j rho_j
/// (k_j: volume j's extinction over the grid's, grey where their hues differ), whose colour
/// grid is each voxel's scattering albedo, sum_j k_j rho_j a_j c_j / sum_j k_j rho_j (a_j:
/// volume j's scatter over its extinction, c_j: its colour grid, in the working space), and
/// whose emission grid, with a colour per voxel, is the sum of every volume's emitted light
/// (constant emission x density, emission grids, blackbody of temperature grids at each
/// voxel). The settings' medium then has albedo 1 (absorb 0, scatter = the grid's
/// extinction), and colours are in the working space (inputToWorking the identity).
/// @a channel 0, 1 or 2: every medium grey at that channel's coefficients, so that the mix is
/// exact in that channel of the image (MixedFrame::proportional); -1: as they are.
MixedFrame mixMaterials(const GridSource::Impl& grid, const RenderSettings& settings, int channel = -1);

} // namespace detail
} // namespace vdb_ewa
