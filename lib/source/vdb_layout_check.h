/// @file vdb_layout_check.h
/// @brief What a .vdb file's header promises, checked against the file before OpenVDB reads
///        it (docs/numerics.md#damaged-files).
///
/// OpenVDB's reader does not check its stream after each read: a file cut or damaged in its
/// header makes it take a length from bytes it never read and allocate that much (a cut at
/// byte 162 of a 200 KB file: 30 s and 20 GB before an error), and a damaged block size below
/// the root overruns its buffers. The file's lengths, counts and offsets are walked here first,
/// each against the bytes the file has: the file header, the file's metadata, each grid's
/// descriptor (name, type, offsets), and at each grid's offset its compression flags, metadata
/// (fixed-size values at their size, the delayed-load metadata's counts and blocks too),
/// transform type and root node counts; for 5-4-3 trees of non-bool values also every node's masks and compressed blocks (blosc headers included) and every
/// leaf buffer, in OpenVDB's reading order, half floats as the grid's is_saved_as_half_float
/// says. Instances (no tree of their own) stop after the transform. 4-7 % of the time OpenVDB
/// takes to read the shared assets. Formats older than 222 (OpenVDB 2.0) are refused. Streams
/// without grid offsets (io::Stream's layout: each grid inline after its descriptor) are walked
/// grid after grid up to the first tree not walked (its end is not known without offsets).
#pragma once

#include <string>

namespace vdb_ewa {
namespace detail {

/// @throw IoError "PATH: damaged VDB file: WHAT at byte N ..." when a length, count or offset
/// of the header runs past the end of the file or is out of order. A file that is not a VDB
/// file (another magic number) passes, for OpenVDB to say so.
void checkVdbLayout(const std::string& path);

} // namespace detail
} // namespace vdb_ewa
