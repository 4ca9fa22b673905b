/// @file vdb_ewa.h
/// @brief Umbrella header of the vdb_ewa library: EWA volume splatting of OpenVDB grids.
#pragma once

#include "camera.h"
#include "camera_file.h"
#include "color_management.h"
#include "error.h"
#include "ewa_kernel.h"
#include "export.h"
#include "exr_output.h"
#include "frame.h"
#include "grid_source.h"
#include "image.h"
#include "make_grid.h"
#include "output_file.h"
#include "environment.h"
#include "image_output.h"
#include "render_settings.h"
#include "interrupter.h"
#include "renderer.h"
#include "scene.h"
#include "render_stats.h"
#include "slab_share.h"
#include "types.h"

namespace vdb_ewa {

/// Library version and the git commit it was configured from, "MAJOR.MINOR.PATCH (git COMMIT)"
/// (COMMIT "unknown" outside a git checkout, "-dirty" with changed tracked files).
VDB_EWA_API const char* versionString();

} // namespace vdb_ewa
