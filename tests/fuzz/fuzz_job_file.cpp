/// @file fuzz_job_file.cpp
/// @brief libFuzzer harness over the job-file parser: the input is a --job file, applied to
///        `vdb_ewa render --job FILE` and checked as the CLI checks it before reading the grid.
///        Any std::exception is a clean refusal (main.cpp prints it as one line); a crash, a
///        sanitizer report, a timeout or a memory blow-up is a finding.
#include "command_line.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static const std::string path = "/tmp/vdb_ewa_fuzz_" + std::to_string(::getpid()) + ".json";
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        vdb_ewa::cli::CommandLine commandLine;
        commandLine.parse({"render", "--job", path}).validate();
    } catch (const std::exception&) {
        // a clean refusal (CLI::Error and vdb_ewa::Error are both std::exceptions)
    }
    std::remove(path.c_str());
    return 0;
}
