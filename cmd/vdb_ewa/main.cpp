/// @file main.cpp
/// @brief vdb_ewa: argv -> a subcommand; the one place that prints errors and picks exit codes.
#include "command_line.h"
#include "exit_codes.h"
#include "error_messages.h"

#include <vdb_ewa/vdb_ewa.h>

#include <iostream>
#include <new>
#include <stdexcept>

namespace {

/// Every error is one line: "vdb_ewa: " and the message (errorLine).
void printError(const std::exception& e)
{
    std::cerr << vdb_ewa::cli::errorLine(dynamic_cast<const std::bad_alloc*>(&e)
            ? "out of memory: the render needed more than this machine could give (std::bad_alloc)"
            : e.what(), "vdb_ewa: ")
              << "\n";
}

} // namespace

int main(int argc, char* argv[])
{
    using namespace vdb_ewa::cli;
    CommandLine commandLine;
    Command* command = nullptr;
    try {
        command = &commandLine.parse({argv + 1, argv + argc});
    } catch (const CLI::Success& e) { // --help, --version
        return commandLine.app().exit(e);
    } catch (const CLI::ParseError& e) {
        printError(std::runtime_error(inOurWords(e) + " (see vdb_ewa --help)"));
        return kExitBadArguments;
    } catch (const std::exception& e) { // a --job file's error
        printError(e);
        return exitCodeFor(e);
    }
    try {
        return command->run();
    } catch (const std::exception& e) {
        printError(e);
        return exitCodeFor(e);
    }
}
