/// @file exit_codes.h
/// @brief The CLI's documented exit codes (README.md, "Exit codes").
#pragma once

namespace vdb_ewa::cli {

constexpr int kExitOk = 0;
constexpr int kExitBadArguments = 2; ///< unknown option, malformed value, impossible camera
constexpr int kExitBadInput = 3;     ///< input file missing, unreadable, wrong grid or type
constexpr int kExitRenderFailed = 4; ///< rendering or writing the output failed

} // namespace vdb_ewa::cli
