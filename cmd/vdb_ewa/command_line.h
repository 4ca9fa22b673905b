/// @file command_line.h
/// @brief The CLI's command line: the app with its subcommands, and argv parsed into the one
///        selected (vdb_render's one-dash spelling and --job files included). main.cpp and the
///        option and job-file fuzzers (tests/fuzz/) share it.
#pragma once

#include "commands.h"

#include <memory>
#include <string>
#include <vector>

namespace vdb_ewa::cli {

class CommandLine
{
public:
    CommandLine();

    /// Parse @a args (argv without the program name) and return the selected subcommand.
    /// @throw CLI::Success for --help and --version (app().exit prints them), CLI::ParseError,
    ///        vdb_ewa::Error from a --job file.
    Command& parse(std::vector<std::string> args);

    CLI::App& app() { return mApp; }

private:
    CLI::App mApp;
    std::vector<std::unique_ptr<Command>> mCommands;
};

} // namespace vdb_ewa::cli
