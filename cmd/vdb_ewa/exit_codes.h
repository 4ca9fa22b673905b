/// @file exit_codes.h
/// @brief The CLI's documented exit codes (README.md, "Exit codes").
#pragma once

#include <vdb_ewa/error.h>
#include <vdb_ewa/interrupter.h>

#include <exception>

namespace vdb_ewa::cli {

constexpr int kExitOk = 0;
constexpr int kExitIncomplete = 1;   ///< `vdb_ewa status`: some frame is not done (docs/farm.md)
constexpr int kExitBadArguments = 2; ///< unknown option, malformed value, impossible camera
constexpr int kExitBadInput = 3;     ///< input file missing, unreadable, wrong grid or type
constexpr int kExitRenderFailed = 4; ///< rendering or writing the output failed
constexpr int kExitOverBudget = 5;   ///< the frame would need more memory than --max-memory allows
constexpr int kExitInterrupted = 130; ///< stopped by SIGINT or SIGTERM (the shell's 128 + SIGINT)

/// The exit code for a failure that threw @a e.
inline int exitCodeFor(const std::exception& e)
{
    if (dynamic_cast<const Cancelled*>(&e)) return kExitInterrupted;
    if (dynamic_cast<const ValueError*>(&e)) return kExitBadArguments;
    if (dynamic_cast<const BudgetError*>(&e)) return kExitOverBudget;
    if (dynamic_cast<const IoError*>(&e) || dynamic_cast<const InputError*>(&e)) return kExitBadInput;
    return kExitRenderFailed;
}

} // namespace vdb_ewa::cli
