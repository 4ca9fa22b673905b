/// @file exr_header.h
/// @brief The header of a flat or deep EXR as plain values, computed once from ExrOptions and
///        applied by either writer (OpenEXR's C++ one, exr_output.cpp, or the zip writer on
///        OpenEXRCore, exr_zip_writer.cpp), and the half conversion both use. Attributes:
///        docs/output.md.
#pragma once

#include <vdb_ewa/exr_output.h>

#include <Imath/half.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vdb_ewa {
namespace detail {

struct ExrHeader
{
    int width = 0, height = 0;
    ExrCompression compression = ExrCompression::Zip;
    std::optional<Chromaticities> chromaticities;
    /// worldToCamera and worldToNDC in OpenEXR's row-vector convention, row by row (Imath's
    /// M44f memory order), and the screen window's width; set when a camera is given.
    std::optional<std::array<float, 16>> worldToCamera, worldToNdc;
    float screenWindowWidth = 1.0f;
    std::vector<std::pair<std::string, std::string>> strings; ///< extra string attributes
};

/// The header @a options ask for a @a width x @a height image.
ExrHeader exrHeader(int width, int height, const ExrOptions& options);

/// float -> half, finite values beyond the half range clamped to +-65504 instead of becoming inf.
inline half toHalf(float v)
{
    return half(std::isfinite(v) ? std::clamp(v, -float(HALF_MAX), float(HALF_MAX)) : v);
}

} // namespace detail
} // namespace vdb_ewa
