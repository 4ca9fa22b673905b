/// @file option_values.h
/// @brief Parsing of vdb_render-style option values ("X,Y,Z", "WxH") and of its
///        single-dash long options ("-translate" is read as "--translate").
#pragma once

#include <vdb_ewa/error.h>
#include <vdb_ewa/types.h>

#include <set>
#include <string>
#include <utility>
#include <vector>

namespace vdb_ewa::cli {

/// Comma-separated numbers; @throw ValueError naming @a option on a malformed list.
std::vector<double> parseNumbers(const std::string& option, const std::string& text);
/// "X,Y,Z", or one number for all three (vdb_render's strToVec3d).
Vec3d parseVec3(const std::string& option, const std::string& text, bool allowBroadcast);
/// A number as -v and the EXR header print it (6 significant digits).
std::string fmt(double v);
/// "X,Y,Z" of fmt().
std::string fmt3(const Vec3d& v);

/// --image-lod: "off" (0) or a number of samples (SplatOptions::imageLod, whose range
/// RenderSettings::validate checks); @throw ValueError on anything else.
double parseImageLod(const std::string& text);
/// --image-lod as -v and the EXR header print it: "off" for 0.
std::string imageLodName(double samples);

/// "WxH" or "W,H", both >= 1.
void parseResolution(const std::string& text, int& width, int& height);

/// A size in bytes: a number with an optional K, M, G or T suffix (powers of 1024; "16G",
/// "512M", "1.5T"). @throw ValueError naming --@a option.
double parseBytes(const std::string& option, const std::string& text);
/// The named values of an option with a fixed set of words ("--exp incremental|exact|table").
template <typename T>
using Choices = std::vector<std::pair<std::string, T>>;

/// "a, b or c": the words of @a choices, for error messages.
template <typename T>
std::string choiceList(const Choices<T>& choices)
{
    std::string list;
    for (std::size_t i = 0; i < choices.size(); ++i) {
        list += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i].first;
    }
    return list;
}

/// The value named @a text; @throw ValueError "--option: expected a, b or c, got 'text'".
template <typename T>
T parseChoice(const std::string& option, const std::string& text, const Choices<T>& choices)
{
    for (const auto& [name, value] : choices) {
        if (name == text) return value;
    }
    throw ValueError("--" + option + ": expected " + choiceList(choices) + ", got '" + text + "'");
}

/// The word naming @a value (for -v, which prints the resolved options).
template <typename T>
std::string choiceName(T value, const Choices<T>& choices)
{
    for (const auto& [name, v] : choices) {
        if (v == value) return name;
    }
    return "?";
}

/// Rewrite "-name" to "--name" for every long option name in @a longNames (vdb_render's
/// spelling); negative numbers and short options pass unchanged.
std::vector<std::string> normalizeSingleDashOptions(const std::vector<std::string>& args,
    const std::set<std::string>& longNames);

} // namespace vdb_ewa::cli
