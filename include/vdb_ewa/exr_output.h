/// @file exr_output.h
/// @brief Frame -> OpenEXR (flat or deep scanline), with the header fields compositors read.
///        No Imf types here. Channel layout and attributes: docs/output.md.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "camera.h"
#include "color_management.h"
#include "frame.h"
#include "output_file.h"

namespace vdb_ewa {

enum class ExrPixelType { Half, Float };
enum class ExrCompression { None, Rle, Zip, Zips, Piz, Dwaa, Dwab };

/// True for the compressions OpenEXR 3.1 accepts for deep scanline files: none, rle, zips.
VDB_EWA_API bool validForDeep(ExrCompression compression);

struct ExrOptions
{
    ExrPixelType colorType = ExrPixelType::Half;   ///< R, G, B, A and the colour passes; Z is always float
    ExrCompression compression = ExrCompression::Zip;
    /// Deflate's level for zip and zips, 1 (fastest) to 9 (smallest), zlib's scale. 1 by default.
    /// Flat zip and zips files are deflated by libdeflate (docs/performance.md#writing-the-file),
    /// deep zips files by OpenEXR's zlib.
    int zipLevel = 1;
    std::optional<Chromaticities> chromaticities;   ///< of the colour space the file holds
    const Camera* camera = nullptr;                 ///< worldToCamera, worldToNDC, screen window
    std::vector<std::pair<std::string, std::string>> attributes; ///< extra string attributes
};

/// Write @a frame's beauty (R, G, B, A) and every pass it holds (Z; transmittance.R/G/B,
/// shadow.R/G/B, emission.R/G/B) to a flat scanline EXR, through a temporary file renamed over
/// @a path. @throw IoError naming the path and the problem.
VDB_EWA_API void writeExr(const Frame& frame, const std::string& path, const ExrOptions& options);

/// Write @a deep as a deep scanline EXR (R, G, B, A premultiplied, Z, ZBack; tidy).
/// @throw ValueError if options.compression is not valid for deep data; IoError on failure.
VDB_EWA_API void writeDeepExr(const DeepImage& deep, const std::string& path, const ExrOptions& options);

/// Write @a image as float R, G, B, A, ZIP, with @a attributes (vdb_render's file type).
VDB_EWA_API void writeExr(const Image& image, const std::string& path,
    const std::vector<std::pair<std::string, std::string>>& attributes = {});

/// Let OpenEXR compress with @a threads threads (0, or more than the cores: all cores).
/// Process-wide (OpenEXR's global thread pool): for applications such as the CLI, not for
/// plugins inside a host. @throw BudgetError if the system cannot start them.
VDB_EWA_API void setExrThreadsProcessWide(int threads);

/// Read an RGBA EXR written by us or by vdb_render (for tests and benchmarks).
/// @throw IoError naming the path.
VDB_EWA_API Image readExr(const std::string& path);

} // namespace vdb_ewa
