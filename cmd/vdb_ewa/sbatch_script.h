/// @file sbatch_script.h
/// @brief The batch script `vdb_ewa submit` hands to Slurm's sbatch: a job array, one task per
///        chunk of frames, each running `vdb_ewa render --job ... --chunk N` (docs/farm.md).
#pragma once

#include <string>
#include <vector>

namespace vdb_ewa::cli {

struct SbatchRequest
{
    std::string program;        ///< the vdb_ewa binary, absolute
    std::string jobFile;        ///< absolute
    std::vector<int> frames;    ///< the frames to render, in order
    int chunk = 1;              ///< frames a task
    bool skipExisting = false;  ///< tasks skip frames whose outputs exist
    long long submitted = 0;    ///< seconds since 1970: a requeued task skips the frames written since
    std::string workingFolder;  ///< the tasks' working folder (relative paths in the job resolve there)
    std::string logFolder;      ///< the tasks' logs go to <logFolder>/<job id>_<task>.log
    std::string name;           ///< --job-name
    std::string partition, memory, time; ///< empty: the cluster's defaults
    int cpus = 0;               ///< --cpus-per-task; 0: the cluster's default
    int maxRunning = 0;         ///< the array's %limit; 0: none
    std::vector<std::string> extra; ///< more sbatch options, one #SBATCH line each
    std::string commandLine;    ///< the submit command, for a comment
};

/// The script's text.
/// @throw ValueError for a value an #SBATCH line cannot hold (a line break, a quote or a
///        backslash in a path; a space, quote or '#' in an --sbatch-option).
std::string sbatchScript(const SbatchRequest& request);

/// @a word quoted for a POSIX shell where it needs to be ('it'\''s').
std::string shellQuoted(const std::string& word);

} // namespace vdb_ewa::cli
