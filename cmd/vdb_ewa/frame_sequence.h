/// @file frame_sequence.h
/// @brief Frame sequences: `--frames` lists (1-240, 1-100x5, 1-10,20) and frame patterns in
///        paths (`####` padded to the number of #, or printf's `%04d` / `%d`).
#pragma once

#include <string>
#include <vector>

namespace vdb_ewa::cli {

/// Parse a frame list: comma-separated items `N`, `A-B` or `A-BxS` (A <= B, S >= 1); frames
/// may be negative (`-5--1`). Frames keep the order given; repeats are dropped.
/// @throw ValueError naming --frames and the item at fault.
std::vector<int> parseFrameList(const std::string& spec);

/// True if @a path holds a frame pattern (a run of '#', or `%d` / `%0Nd`).
bool hasFramePattern(const std::string& path);

/// @a path with its frame pattern replaced by @a frame (zero-padded to the pattern's width,
/// a minus sign before the digits). @throw ValueError if @a path holds more than one pattern.
std::string framePath(const std::string& path, int frame);

/// The frames of array task @a task (0-based) when @a frames are cut into chunks of @a chunk
/// frames in their order: frames [task * chunk, (task + 1) * chunk), the last chunk shorter.
/// @throw ValueError naming --chunk or --task when @a chunk < 1 or the task has no chunk.
std::vector<int> frameChunk(const std::vector<int>& frames, int chunk, int task);

/// The number of chunks of @a chunk frames that @a frameCount frames make.
int chunkCount(std::size_t frameCount, int chunk);

/// @a frames as a frame list parseFrameList reads back in the same order: runs of consecutive
/// frames as A-B, the rest comma-separated (1-4,9,11-12).
std::string frameListText(const std::vector<int>& frames);

} // namespace vdb_ewa::cli
