/// @file atomic_write.h
/// @brief Write a file through a temporary file in the same folder, renamed over the
///        destination only once complete: a failure, a full disk or a kill never leaves a
///        damaged or partial destination, and a pre-existing file stays byte-identical.
#pragma once

#include <functional>
#include <string>

namespace vdb_ewa {
namespace detail {

/// Call @a write with a temporary path next to @a path, then rename it over @a path. On any
/// exception the temporary file is removed; vdb_ewa errors pass through, others become an
/// IoError "PATH: cannot write WHAT (reason)".
void writeAtomically(const std::string& path, const std::string& what,
    const std::function<void(const std::string& temporaryPath)>& write);

} // namespace detail
} // namespace vdb_ewa
