/// @file exr_zip_writer.h
/// @brief Flat scanline EXRs compressed zip (16 lines a chunk) or zips (one), written through
///        OpenEXRCore with each chunk deflated by libdeflate, on several threads and in order.
///        OpenEXR 3.1's own writer deflates with zlib, at about 40 MB/s a core at level 1 on a
///        float frame: libdeflate takes a third to half of its time for a smaller file
///        (docs/performance.md#writing-the-file). The bytes are EXR's zip, so any reader reads
///        them: the bytes split into even and odd halves, each byte replaced by its difference
///        from the one before, then a zlib stream (OpenEXR's ImfZip.cpp does the same).
#pragma once

#include "output/exr_header.h"

#include <cstddef>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// One channel of a flat EXR: the value of pixel (x, y) at values[(y * width + x) * stride].
struct ExrPlane
{
    std::string name;
    const float* values = nullptr;
    std::size_t stride = 1;
    bool half = false; ///< written as half, finite values clamped to its range (toHalf)
};

/// Write @a planes under @a header, whose compression is Zip or Zips, to @a path itself (callers
/// go through writeAtomically). @a level: deflate's, 1 (fastest) to 9. Threads: OpenEXR's global
/// count (setExrThreadsProcessWide), at least one. @throw std::runtime_error saying what failed
/// (writeAtomically names the destination).
void writeZipExr(const std::string& path, const ExrHeader& header, std::vector<ExrPlane> planes, int level);

/// EXR's zip of one chunk: @a raw reordered and differenced, then deflated into @a out at @a level
/// (a fresh compressor each call: for tests; the writer keeps one a thread). @a out holds @a raw
/// itself when deflate does not make it smaller, as the format asks.
void zipChunk(const std::vector<unsigned char>& raw, int level, std::vector<unsigned char>& out);

} // namespace detail
} // namespace vdb_ewa
