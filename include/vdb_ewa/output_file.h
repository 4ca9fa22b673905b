/// @file output_file.h
/// @brief Output paths: checked before rendering, written through a temporary file.
#pragma once

#include <string>

#include "types.h"

namespace vdb_ewa {

/// Check, before rendering, that @a path can be written: its folder exists and is writable,
/// and it is not a folder or a read-only file. @throw IoError naming the path and the problem.
VDB_EWA_API void checkOutputWritable(const std::string& path);

/// Remove the temporary files of the writes in progress: every output is written to a hidden
/// temporary file next to it and renamed over it once complete, so removing them leaves no
/// trace of an unfinished write (finished outputs are never touched). Async-signal-safe: no
/// locks, no allocation, only unlink(2). For a host that must end its process at once, from a
/// signal handler or a watchdog thread, just before _exit (the CLI does, docs/reliability.md).
VDB_EWA_API void removeTemporaryOutputs() noexcept;

} // namespace vdb_ewa
