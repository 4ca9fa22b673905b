/// @file rgb.h
/// @brief One colour per kernel (material colours, per-kernel shadows): plain data between stages.
#pragma once

#include <array>

namespace vdb_ewa {
namespace detail {

using Rgb = std::array<float, 3>;

} // namespace detail
} // namespace vdb_ewa
