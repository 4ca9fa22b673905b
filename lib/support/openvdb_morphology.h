/// @file openvdb_morphology.h
/// @brief OpenVDB's dilation and erosion, with default symbol visibility (see openvdb.h); apart
///        from openvdb_tools.h because few files need it and it is heavy to compile.
#pragma once

#include "support/openvdb.h"

#pragma GCC visibility push(default)
#include <openvdb/tools/Morphology.h>
#pragma GCC visibility pop
