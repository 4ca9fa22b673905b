/// @file job_file.h
/// @brief `--job shot.json`: a JSON object whose keys are the render command's long option
///        names (and `input`, `output`), so a job file says everything the command line can.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

namespace vdb_ewa::cli {

/// Read the job file @a path and return its settings as command-line arguments, leaving out
/// every option in @a givenOnCommandLine (the command line overrides the job) and the
/// positionals when @a positionalsGiven. @a knownOptions: the long option names the render
/// command accepts (without dashes); @a flags: those that take no value.
/// Values: strings as they are, numbers, true/false for flags and on/off switches, arrays of
/// numbers joined with commas (`"translate": [0, 0, 5]`), arrays of strings joined
/// (`"aov": ["shadow", "emission"]`), arrays of arrays repeat the option once per inner array
/// (`"light": [[1, 1, 0], [-1, 0.5, 0, 0.2, 0.3, 0.6]]`). One key is not an option: `volumes`,
/// a list of objects `{"file": F, "grid": G, "transform": [[4 rows of 4]]}` (grid and transform
/// optional) with, optionally, the volume's own optical model (`absorb`, `scatter`, `emission`,
/// `color`, `emission-grid`, `temperature`), given as --add-volume F:G, --add-volume-transform
/// and --add-volume-material, one each.
/// @throw IoError (unreadable, not JSON) or ValueError (unknown key, wrong value) naming the
///        file and the key.
std::vector<std::string> jobArguments(const std::string& path, const std::vector<std::string>& knownOptions,
    const std::vector<std::string>& flags, const std::vector<std::string>& givenOnCommandLine, bool positionalsGiven);

/// The command-line arguments of the option --@a key set to @a value (a job file's entry, or a
/// Python keyword argument), by the rules above; @a flag: the option takes no value (true
/// gives it, false leaves it out). @a where names the entry in errors.
/// @throw ValueError for a value of the wrong kind.
std::vector<std::string> optionArguments(const std::string& key, const nlohmann::json& value, bool flag, const std::string& where);

/// The deepest nesting of lists and objects a job or camera file may hold (they need two).
constexpr int kMaxJsonDepth = 64;

/// The JSON object in the regular file @a path (a directory or a FIFO is refused before it is
/// opened: a FIFO with no writer would block the open). @a kind names the file in errors ("job",
/// "camera"), @a entries what its object holds ("option: value").
/// @throw IoError (not a regular file, unreadable, not JSON, nested deeper than kMaxJsonDepth)
///        or ValueError (not an object).
nlohmann::json readJsonObjectFile(const std::string& path, const std::string& kind, const std::string& entries);

/// If @a args (the render subcommand's arguments, after the subcommand's name) hold
/// `--job FILE` (or `--job=FILE`), return them with the job's settings inserted before them
/// and `--job FILE` removed; else return them as they are. @a render supplies the option names.
std::vector<std::string> applyJobFile(const std::vector<std::string>& args, const CLI::App& render);

} // namespace vdb_ewa::cli
