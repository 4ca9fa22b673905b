/// @file fuzz_options.cpp
/// @brief libFuzzer harness over the option parser: the input is a command line, one argument
///        per line, parsed as main.cpp parses argv and checked as the CLI checks it before
///        reading the grid. Any std::exception is a clean refusal; a crash, a sanitizer report,
///        a timeout or a memory blow-up is a finding.
#include "command_line.h"

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    std::vector<std::string> args(1);
    for (std::size_t i = 0; i < size; ++i) {
        if (data[i] == '\n') args.emplace_back();
        else args.back() += char(data[i]);
    }
    try {
        vdb_ewa::cli::CommandLine commandLine;
        commandLine.parse(args).validate();
    } catch (const std::exception&) {
        // a clean refusal (CLI::Error and vdb_ewa::Error are both std::exceptions)
    }
    return 0;
}
