/// @file commands.h
/// @brief The CLI's subcommands: each registers its options on a CLI11 app and runs them.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <set>
#include <string>
#include <vector>

namespace vdb_ewa::cli {

/// A subcommand: registered on the app, run if it was selected.
class Command
{
public:
    virtual ~Command() = default;
    virtual CLI::App* subcommand() const = 0;
    /// Check the parsed arguments without reading or writing a file (run() checks them too).
    /// @throw vdb_ewa::ValueError naming the option
    virtual void validate() const = 0;
    /// @return an exit code (exit_codes.h); throws vdb_ewa::Error on failure.
    virtual int run() = 0;
};

std::unique_ptr<Command> addRenderCommand(CLI::App& app);
std::unique_ptr<Command> addMakeGridCommand(CLI::App& app);
std::unique_ptr<Command> addSubmitCommand(CLI::App& app);
std::unique_ptr<Command> addStatusCommand(CLI::App& app);

/// What a render command line renders: its frames and the paths of their files.
struct RenderJob
{
    std::vector<int> frames;   ///< --frames in order (every chunk's); {0} without --frames
    bool sequence = false;     ///< --frames was given: the paths hold frame patterns
    std::string input, output; ///< as given (with their frame patterns)
    std::string preview;       ///< --preview as given; empty without one
    bool skipExisting = false;

    /// @a pattern (input, output or preview) of @a frame.
    std::string pathOf(const std::string& pattern, int frame) const;
    /// The frame is done: its output exists, and its preview if one is asked for (outputs are
    /// renamed into place whole, so an existing one is complete). Relative paths are taken in
    /// @a folder where it is not empty (the tasks' working folder), else in the current one.
    bool done(int frame, const std::string& folder = "") const;
};

/// Parse and check @a renderArguments (the render subcommand's, `--job FILE` applied as the CLI
/// applies it) as `vdb_ewa render` would before reading any grid.
/// @throw CLI::ParseError, vdb_ewa::Error (ValueError, IoError) as the render would
RenderJob renderJobOf(const std::vector<std::string>& renderArguments);

/// renderJobOf `--job @a jobFile` (and `--frames @a frames` unless empty): what submit and
/// status act on.
RenderJob renderJobOfFile(const std::string& jobFile, const std::string& frames);

} // namespace vdb_ewa::cli
