/// @file main.cpp
/// @brief vdb_ewa: argv -> a subcommand; the one place that prints errors and picks exit codes.
#include "command_line.h"
#include "exit_codes.h"

#include <vdb_ewa/vdb_ewa.h>

#include <iostream>
#include <new>
#include <stdexcept>

namespace {

/// Every error is one line of at most 300 characters: "vdb_ewa: " and the message, control
/// characters blanked (a file's garbage grid name once printed 1.6 GB), clipped at a UTF-8
/// character boundary.
void printError(const std::exception& e)
{
    std::string line = "vdb_ewa: ";
    line += dynamic_cast<const std::bad_alloc*>(&e) ? "out of memory: the render needed more than this machine could give (std::bad_alloc)"
                                                    : e.what();
    for (char& c : line) {
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
    }
    constexpr std::size_t kMaxLine = 300;
    if (line.size() > kMaxLine) {
        std::size_t cut = kMaxLine - 3;
        while (cut > 0 && (static_cast<unsigned char>(line[cut]) & 0xc0) == 0x80) --cut;
        line = line.substr(0, cut) + "...";
    }
    std::cerr << line << "\n";
}

} // namespace

int main(int argc, char* argv[])
{
    using namespace vdb_ewa::cli;
    CommandLine commandLine;
    Command* command = nullptr;
    try {
        command = &commandLine.parse({argv + 1, argv + argc});
    } catch (const CLI::Success& e) { // --help, --help-all, --version
        return commandLine.app().exit(e);
    } catch (const CLI::ParseError& e) {
        printError(std::runtime_error(std::string(e.what()) + " (see vdb_ewa --help)"));
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
