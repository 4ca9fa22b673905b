/// @file error_messages.h
/// @brief Error messages as the CLI prints them and the Python module raises them: one line,
///        CLI11's parse errors in our words.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace vdb_ewa::cli {

/// @a prefix and @a message as one line of at most 300 characters: control characters blanked
/// (a file's garbage grid name once printed 1.6 GB), clipped at a UTF-8 character boundary.
std::string errorLine(const std::string& message, const std::string& prefix = "");

/// @a e as one line saying what is wrong and what to do ("--refine: 'x' is not a valid value").
std::string inOurWords(const CLI::ParseError& e);

} // namespace vdb_ewa::cli
