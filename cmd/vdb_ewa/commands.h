/// @file commands.h
/// @brief The CLI's subcommands: each registers its options on a CLI11 app and runs them.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <set>
#include <string>

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

} // namespace vdb_ewa::cli
