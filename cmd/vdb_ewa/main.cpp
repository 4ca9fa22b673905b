/// @file main.cpp
/// @brief vdb_ewa: argv -> a subcommand; the one place that prints errors and picks exit codes.
#include "command_line.h"
#include "exit_codes.h"

#include <vdb_ewa/vdb_ewa.h>

#include <iostream>
#include <new>
#include <regex>
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

/// CLI11's parse errors in our words: what is wrong and what to do.
std::string inOurWords(const CLI::ParseError& e)
{
    const std::string what = e.what();
    std::smatch m;
    if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
        const std::size_t colon = what.find(": ");
        return "unknown option or one argument too many: " + (colon == std::string::npos ? what : what.substr(colon + 2));
    }
    if (std::regex_match(what, m, std::regex("Could not convert: (\\S+) = (.*)"))) {
        return std::string(m[1]) + ": '" + std::string(m[2]) + "' is not a valid value";
    }
    if (std::regex_match(what, m, std::regex("(\\S+): \\d+ required \\S+ missing"))) return std::string(m[1]) + " needs a value";
    if (std::regex_match(what, m, std::regex("(input|output) is required"))) {
        return "no " + std::string(m[1]) + " given: vdb_ewa IN.vdb OUT.exr [options]";
    }
    if (what == "kind is required") return "no grid kind given: vdb_ewa make-grid KIND OUT.vdb";
    return what;
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
