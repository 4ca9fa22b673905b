/// @file option_values.h
/// @brief Parsing of vdb_render-style option values ("X,Y,Z", "WxH") and of its
///        single-dash long options ("-translate" is read as "--translate").
#pragma once

#include <vdb_ewa/types.h>

#include <set>
#include <string>
#include <vector>

namespace vdb_ewa::cli {

/// Comma-separated numbers; @throw ValueError naming @a option on a malformed list.
std::vector<double> parseNumbers(const std::string& option, const std::string& text);
/// "X,Y,Z", or one number for all three (vdb_render's strToVec3d).
Vec3d parseVec3(const std::string& option, const std::string& text, bool allowBroadcast);
/// "WxH" or "W,H", both >= 1.
void parseResolution(const std::string& text, int& width, int& height);
/// Rewrite "-name" to "--name" for every long option name in @a longNames (vdb_render's
/// spelling); negative numbers and short options pass unchanged.
std::vector<std::string> normalizeSingleDashOptions(const std::vector<std::string>& args,
    const std::set<std::string>& longNames);

} // namespace vdb_ewa::cli
