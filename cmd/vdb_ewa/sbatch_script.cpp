/// @file sbatch_script.cpp
#include "sbatch_script.h"

#include "frame_sequence.h"

#include <vdb_ewa/error.h>

#include <sstream>

namespace vdb_ewa::cli {

std::string shellQuoted(const std::string& word)
{
    const bool plain = !word.empty() && word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=/.,:@%") == std::string::npos;
    if (plain) return word;
    std::string quoted = "'";
    for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

std::string sbatchScript(const SbatchRequest& r)
{
    const int tasks = chunkCount(r.frames.size(), r.chunk);
    std::ostringstream s;
    const auto directive = [&](const std::string& option) {
        if (option.find_first_of("\n\r") != std::string::npos) throw ValueError("submit: an sbatch option holds a line break: " + shellQuoted(option));
        s << "#SBATCH " << option << "\n";
    };
    s << "#!/bin/sh\n";
    directive("--job-name=" + shellQuoted(r.name));
    directive("--array=0-" + std::to_string(tasks - 1) + (r.maxRunning > 0 ? "%" + std::to_string(r.maxRunning) : ""));
    directive("--output=" + shellQuoted(r.logPattern));
    directive("--open-mode=append"); // a requeued task adds to its log
    directive("--chdir=" + shellQuoted(r.workingFolder));
    if (r.cpus > 0) directive("--cpus-per-task=" + std::to_string(r.cpus));
    if (!r.memory.empty()) directive("--mem=" + r.memory);
    if (!r.time.empty()) directive("--time=" + r.time);
    if (!r.partition.empty()) directive("--partition=" + r.partition);
    for (const std::string& e : r.extra) directive(e);
    std::string comment = r.commandLine;
    for (char& c : comment) c = c == '\n' || c == '\r' ? ' ' : c;
    s << "# Written by: " << comment << "\n"
      << "# " << r.frames.size() << " frames in " << tasks << " task" << (tasks == 1 ? "" : "s") << " of " << r.chunk
      << ": task I renders frames [I*" << r.chunk << ", (I+1)*" << r.chunk << ") of --frames (docs/farm.md).\n"
      << "# exec: scancel's and preemption's SIGTERM reach vdb_ewa, which leaves no partial frame.\n"
      << "cd " << shellQuoted(r.workingFolder) << " || exit 3 # as --chdir, for a task run by hand: sh this.sbatch\n"
      << "exec " << shellQuoted(r.program) << " render --job " << shellQuoted(r.jobFile) << " --frames " << shellQuoted(frameListText(r.frames))
      << " --chunk " << r.chunk << (r.skipExisting ? " --skip-existing" : "") << "\n";
    return s.str();
}

} // namespace vdb_ewa::cli
