/// @file command_line.cpp
#include "command_line.h"

#include "job_file.h"
#include "option_values.h"

#include <vdb_ewa/vdb_ewa.h>

#include <algorithm>
#include <set>

namespace vdb_ewa::cli {

CommandLine::CommandLine() : mApp("vdb_ewa: EWA volume splatting of OpenVDB fog volumes (Zwicker et al. 2002)", "vdb_ewa")
{
    mApp.require_subcommand(1);
    mApp.set_version_flag("--version", std::string("vdb_ewa ") + vdb_ewa::versionString());
    mCommands.push_back(addRenderCommand(mApp));
    mCommands.push_back(addMakeGridCommand(mApp));
    mCommands.push_back(addSubmitCommand(mApp));
    mCommands.push_back(addStatusCommand(mApp));
}

Command& CommandLine::parse(std::vector<std::string> args)
{
    // vdb_render spells long options with one dash (-translate, -help, -version): accept that too.
    std::set<std::string> longNames;
    for (const CLI::App* app : {&mApp}) {
        for (const CLI::Option* opt : app->get_options()) {
            for (const std::string& n : opt->get_lnames()) longNames.insert(n);
        }
    }
    for (const auto& cmd : mCommands) {
        for (const CLI::Option* opt : cmd->subcommand()->get_options()) {
            for (const std::string& n : opt->get_lnames()) longNames.insert(n);
        }
    }
    args = normalizeSingleDashOptions(args, longNames);
    if (args.empty()) throw CLI::RequiredError("no input or output given: vdb_ewa IN.vdb OUT.exr [options]", CLI::ExitCodes::RequiredError);
    // vdb_render's command line, `vdb_ewa IN OUT [options]`: without a subcommand it is `render`,
    // and `vdb_ewa --help` lists render's options, as `vdb_render -help` lists its own.
    const bool named = std::any_of(mCommands.begin(), mCommands.end(), [&](const auto& cmd) { return cmd->subcommand()->get_name() == args.front(); });
    if (!named && args.front() != "--version") args.insert(args.begin(), "render");
    // --job FILE: the job's settings go before the command line's, which override them.
    if (args.front() == "render") {
        std::vector<std::string> rest = applyJobFile({args.begin() + 1, args.end()}, *mCommands.front()->subcommand());
        rest.insert(rest.begin(), "render");
        args = std::move(rest);
    }
    std::reverse(args.begin(), args.end()); // CLI11 takes a reversed vector
    mApp.parse(args);
    for (const auto& cmd : mCommands) {
        if (cmd->subcommand()->parsed()) return *cmd;
    }
    throw CLI::RequiredError("a subcommand"); // unreachable: require_subcommand(1)
}

} // namespace vdb_ewa::cli
