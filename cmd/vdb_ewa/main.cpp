/// @file main.cpp
/// @brief vdb_ewa: argv -> a subcommand; the one place that prints errors and picks exit codes.
#include "commands.h"
#include "exit_codes.h"
#include "job_file.h"
#include "option_values.h"

#include <vdb_ewa/vdb_ewa.h>

#include <iostream>

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
            std::cerr << "vdb_ewa: " << e.what() << "\n";
            return exitCodeFor(e);
        }
    }
    std::reverse(args.begin(), args.end()); // CLI11 takes a reversed vector

    try {
        app.parse(args);
    } catch (const CLI::Success& e) { // --help, --help-all, --version
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "vdb_ewa: " << e.what() << " (see vdb_ewa --help)\n";
        return kExitBadArguments;
    }

    for (const auto& cmd : commands) {
        if (!cmd->subcommand()->parsed()) continue;
        try {
            return cmd->run();
        } catch (const std::exception& e) {
            std::cerr << "vdb_ewa: " << e.what() << "\n";
            return exitCodeFor(e);
        }
    }
    return kExitBadArguments;
}
