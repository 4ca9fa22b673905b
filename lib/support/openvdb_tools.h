/// @file openvdb_tools.h
/// @brief The OpenVDB tools the library uses, with default symbol visibility (see openvdb.h).
#pragma once

#include "support/openvdb.h"

#pragma GCC visibility push(default)
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Prune.h>
#pragma GCC visibility pop
