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
}

Command& CommandLine::parse(std::vector<std::string> args)
{
    // vdb_render spells long options with one dash (-translate): accept that too.
    std::set<std::string> longNames;
    for (const auto& cmd : mCommands) {
        for (const CLI::Option* opt : cmd->subcommand()->get_options()) {
            for (const std::string& n : opt->get_lnames()) longNames.insert(n);
        }
    }
    args = normalizeSingleDashOptions(args, longNames);
    // --job FILE: the job's settings go before the command line's, which override them.
    if (!args.empty() && args.front() == "render") {
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
