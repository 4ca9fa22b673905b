/// @file main.cpp
/// @brief vdb_ewa: argv -> a subcommand; the one place that prints errors and picks exit codes.
#include "commands.h"
#include "exit_codes.h"
#include "job_file.h"
#include "option_values.h"

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
    CLI::App app{"vdb_ewa: EWA volume splatting of OpenVDB fog volumes (Zwicker et al. 2002)", "vdb_ewa"};
    app.require_subcommand(1);
    app.set_version_flag("--version", std::string("vdb_ewa ") + vdb_ewa::versionString());
    std::vector<std::unique_ptr<Command>> commands;
    commands.push_back(addRenderCommand(app));
    commands.push_back(addMakeGridCommand(app));

    // vdb_render spells long options with one dash (-translate): accept that too.
    std::set<std::string> longNames;
    for (const auto& cmd : commands) {
        for (const CLI::Option* opt : cmd->subcommand()->get_options()) {
            for (const std::string& n : opt->get_lnames()) longNames.insert(n);
        }
    }
    std::vector<std::string> args(argv + 1, argv + argc);
    args = normalizeSingleDashOptions(args, longNames);
    // --job FILE: the job's settings go before the command line's, which override them.
    if (!args.empty() && args.front() == "render") {
        try {
            std::vector<std::string> rest = applyJobFile({args.begin() + 1, args.end()}, *commands.front()->subcommand());
            rest.insert(rest.begin(), "render");
            args = std::move(rest);
        } catch (const std::exception& e) {
            printError(e);
            return exitCodeFor(e);
        }
    }
    std::reverse(args.begin(), args.end()); // CLI11 takes a reversed vector

    try {
        app.parse(args);
    } catch (const CLI::Success& e) { // --help, --help-all, --version
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        printError(std::runtime_error(std::string(e.what()) + " (see vdb_ewa --help)"));
        return kExitBadArguments;
    }

    for (const auto& cmd : commands) {
        if (!cmd->subcommand()->parsed()) continue;
        try {
            return cmd->run();
        } catch (const std::exception& e) {
            printError(e);
            return exitCodeFor(e);
        }
    }
    return kExitBadArguments;
}
