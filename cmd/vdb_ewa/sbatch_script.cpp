/// @file sbatch_script.cpp
#include "sbatch_script.h"

#include "frame_sequence.h"

#include <vdb_ewa/error.h>

#include <cctype>
#include <sstream>

namespace vdb_ewa::cli {
namespace {

/// @a text with its line breaks shown as \n (an error stays one line).
std::string oneLine(std::string text)
{
    for (std::size_t at = text.find_first_of("\r\n"); at != std::string::npos; at = text.find_first_of("\r\n", at + 2)) {
        text.replace(at, 1, text[at] == '\n' ? "\\n" : "\\r");
    }
    return text;
}

/// @a value as an #SBATCH line holds it. sbatch's directive parser ends a value at whitespace
/// outside double quotes and takes a backslash as an escape even inside them: a value with
/// spaces is double-quoted, and a quote, backslash or line break is refused.
std::string directiveValue(const std::string& what, const std::string& value)
{
    if (value.find_first_of("\"\\\r\n") != std::string::npos) {
        throw ValueError("submit: " + what + " '" + oneLine(value) + "' holds a quote, backslash or line break, which an #SBATCH line cannot");
    }
    return value.find_first_of(" \t#'") == std::string::npos ? value : "\"" + value + "\"";
}

} // namespace

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
    const auto directive = [&](const std::string& option, const std::string& value) {
        s << "#SBATCH --" << option << "=" << directiveValue("--" + option, value) << "\n";
    };
    // --output expands %A (job) and %a (task); a '%' of the folder's own is written %%.
    std::string logFolder;
    for (const char c : r.logFolder) logFolder += c == '%' ? std::string("%%") : std::string(1, c);
    // A job name of plain characters: squeue and status columns split at spaces.
    std::string name = r.name;
    for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == ':' ? c : '_';

    s << "#!/bin/sh\n";
    directive("job-name", name);
    directive("array", "0-" + std::to_string(tasks - 1) + (r.maxRunning > 0 ? "%" + std::to_string(r.maxRunning) : ""));
    directive("output", logFolder + "/%A_%a.log");
    directive("open-mode", "append"); // a requeued task adds to its log
    directive("chdir", r.workingFolder);
    if (r.cpus > 0) directive("cpus-per-task", std::to_string(r.cpus));
    if (!r.memory.empty()) directive("mem", r.memory);
    if (!r.time.empty()) directive("time", r.time);
    if (!r.partition.empty()) directive("partition", r.partition);
    for (const std::string& e : r.extra) {
        if (e.size() < 2 || e[0] != '-' || e.find_first_of(" \t\r\n\"'\\#") != std::string::npos) {
            throw ValueError("--sbatch-option: '" + oneLine(e) + "' is not one sbatch option without spaces, quotes or '#' (--account=fx)");
        }
        s << "#SBATCH " << e << "\n";
    }
    s << "# Written by: " << oneLine(r.commandLine) << "\n"
      << "# " << r.frames.size() << " frames in " << tasks << " task" << (tasks == 1 ? "" : "s") << " of " << r.chunk
      << ": task I renders frames [I*" << r.chunk << ", (I+1)*" << r.chunk << ") of --frames (docs/farm.md).\n"
      << "# --skip-newer-than: a requeued task does not redo the frames it wrote before (the submission's time).\n"
      << "# exec: scancel's and preemption's SIGTERM reach vdb_ewa, which leaves no partial frame.\n"
      << "cd " << shellQuoted(r.workingFolder) << " || exit 3 # as --chdir, for a task run by hand: sh this.sbatch\n"
      << "exec " << shellQuoted(r.program) << " render --job " << shellQuoted(r.jobFile) << " --frames " << shellQuoted(frameListText(r.frames))
      << " --chunk " << r.chunk << " --skip-newer-than " << r.submitted << (r.skipExisting ? " --skip-existing" : "") << "\n";
    return s.str();
}

} // namespace vdb_ewa::cli
