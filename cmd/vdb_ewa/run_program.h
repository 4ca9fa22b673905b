/// @file run_program.h
/// @brief Running another program (the scheduler's sbatch and squeue) and reading what it says.
#pragma once

#include <string>
#include <vector>

namespace vdb_ewa::cli {

struct ProgramResult
{
    int exitCode = -1; ///< the exit status; -1 if it could not start, was killed or timed out
    std::string out, err; ///< the first MiB of each
    std::string failure; ///< why exitCode is -1 ("not found", "killed by signal 9", "timed out after 60 s")

    /// Why it failed, in one line: @a failure, else stderr's last line with "error" (Slurm's
    /// commands print warnings first), else its first line, else the exit code; without the
    /// program's own name in front ("sbatch: error: ..." is "error: ...").
    std::string why(const std::string& program) const;
};

/// Run @a program (looked up in PATH when it has no '/') with @a args, its stdin /dev/null,
/// its stdout and stderr read; killed, with anything it started in its process group, after
/// @a timeoutSeconds.
ProgramResult runProgram(const std::string& program, const std::vector<std::string>& args, double timeoutSeconds = 60.0);

} // namespace vdb_ewa::cli
