/// @file job_file.cpp
#include "job_file.h"

#include <vdb_ewa/error.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace vdb_ewa::cli {
namespace {

bool contains(const std::vector<std::string>& list, const std::string& s)
{
    return std::find(list.begin(), list.end(), s) != list.end();
}

/// A scalar as a command-line word.
std::string word(const nlohmann::json& v, const std::string& where)
{
    if (v.is_string()) return v.get<std::string>();
    if (v.is_number_integer()) return std::to_string(v.get<long long>());
    if (v.is_number()) {
        std::ostringstream s;
        s.precision(17);
        s << v.get<double>();
        return s.str();
    }
    if (v.is_boolean()) return v.get<bool>() ? "on" : "off";
    throw ValueError(where + ": expected a string, number or true/false");
}

/// A `volumes` entry's transform as --add-volume-transform's text: a 4x4 (or 3x4) list of rows,
/// or their 16 (or 12) numbers in one list, row by row.
std::string transformText(const nlohmann::json& transform, const std::string& where)
{
    std::string text;
    const auto add = [&](const nlohmann::json& v) {
        if (!v.is_number()) throw ValueError(where + ": expected numbers: a 4x4 matrix as 4 rows (or 3), or its 16 (or 12) numbers row by row");
        text += (text.empty() ? "" : ",") + word(v, where);
    };
    if (!transform.is_array()) throw ValueError(where + ": expected a 4x4 matrix as a list of rows");
    for (const auto& row : transform) {
        if (row.is_array()) {
            for (const auto& v : row) add(v);
        } else {
            add(row);
        }
    }
    return text;
}

/// The job file's `volumes` list as --add-volume, --add-volume-transform and
/// --add-volume-material arguments: each entry an object with `file`, and optionally `grid`,
/// `transform` and its own optical model (`absorb`, `scatter`, `emission`: a number or
/// [R, G, B]; `color`, `emission-grid`, `temperature`: grid names).
std::vector<std::string> volumeArguments(const nlohmann::json& volumes, const std::string& where)
{
    if (!volumes.is_array() || volumes.empty()) throw ValueError(where + ": expected a list of volumes, each {\"file\": ..., \"grid\": ..., \"transform\": ...}");
    std::vector<std::string> args, transforms, materials;
    bool anyTransform = false, anyMaterial = false;
    for (std::size_t i = 0; i < volumes.size(); ++i) {
        const nlohmann::json& v = volumes[i];
        const std::string at = where + "[" + std::to_string(i) + "]";
        if (!v.is_object()) throw ValueError(at + ": expected an object {\"file\": ..., \"grid\": ..., \"transform\": ...}");
        std::string file, grid, transform = "1,0,0,0,0,1,0,0,0,0,1,0", material;
        for (const auto& [key, value] : v.items()) {
            if (key == "file" || key == "grid") {
                if (!value.is_string() || value.get<std::string>().empty()) throw ValueError(at + ": " + key + ": expected a name");
                (key == "file" ? file : grid) = value.get<std::string>();
            } else if (key == "transform") {
                transform = transformText(value, at + ": transform");
                anyTransform = true;
            } else if (key == "absorb" || key == "scatter" || key == "emission") { // its own optical model: --add-volume-material
                std::string rgb;
                for (const auto& c : value.is_array() ? value : nlohmann::json::array({value})) {
                    if (!c.is_number()) throw ValueError(at + ": " + key + ": expected a number or [R, G, B]");
                    rgb += (rgb.empty() ? "" : ",") + word(c, at + ": " + key);
                }
                material += (material.empty() ? "" : " ") + key + "=" + rgb;
            } else if (key == "color" || key == "emission-grid" || key == "temperature") {
                if (!value.is_string() || value.get<std::string>().empty() || value.get<std::string>().find_first_of(" \t") != std::string::npos) {
                    throw ValueError(at + ": " + key + ": expected a grid name (without spaces)");
                }
                material += (material.empty() ? "" : " ") + key + "=" + value.get<std::string>();
            } else {
                throw ValueError(at + ": unknown key '" + key + "' (file, grid, transform, absorb, scatter, emission, color, emission-grid, temperature)");
            }
        }
        if (file.empty()) throw ValueError(at + ": no file");
        args.insert(args.end(), {"--add-volume", grid.empty() ? file : file + ":" + grid});
        transforms.insert(transforms.end(), {"--add-volume-transform", transform});
        materials.insert(materials.end(), {"--add-volume-material", material.empty() ? "same" : material});
        anyMaterial = anyMaterial || !material.empty();
    }
    if (anyTransform) args.insert(args.end(), transforms.begin(), transforms.end());
    if (anyMaterial) args.insert(args.end(), materials.begin(), materials.end());
    return args;
}

} // namespace

std::vector<std::string> optionArguments(const std::string& key, const nlohmann::json& value, bool flag, const std::string& where)
{
    if (flag) {
        if (!value.is_boolean()) throw ValueError(where + ": expected true or false");
        return value.get<bool>() ? std::vector<std::string>{"--" + key} : std::vector<std::string>{};
    }
    std::vector<std::string> args;
    if (value.is_array()) {
        if (value.empty()) throw ValueError(where + ": empty list");
        // A list of lists repeats the option, once per inner list ("light": [[...], [...]]).
        const bool repeated = value.front().is_array();
        for (const auto& item : repeated ? value : nlohmann::json::array({value})) {
            if (!item.is_array() || item.empty()) throw ValueError(where + ": expected a list of numbers or a list of such lists");
            std::string joined;
            for (const auto& element : item) {
                if (element.is_array() || element.is_object()) throw ValueError(where + ": expected a list of numbers or a list of such lists");
                joined += (joined.empty() ? "" : ",") + word(element, where);
            }
            args.push_back("--" + key);
            args.push_back(joined);
        }
        return args;
    }
    if (value.is_object() || value.is_null()) throw ValueError(where + ": expected a string, number, true/false or list");
    return {"--" + key, word(value, where)};
}

nlohmann::json readJsonObjectFile(const std::string& path, const std::string& kind, const std::string& entries)
{
    std::error_code error;
    const auto status = std::filesystem::status(path, error);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
        throw IoError(path + ": not a regular file, so not a " + kind + " file");
    }
    std::ifstream in(path);
    if (!in) throw IoError(path + ": cannot open the " + kind + " file");
    nlohmann::json object;
    try {
        // Nesting is refused as it is read: a million brackets are read without recursion, but
        // what then walks the document (copies, checks, the destructor) recurses and overflows
        // the stack. A job or camera file nests two levels (a list of lists of numbers).
        object = nlohmann::json::parse(in, [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json&) {
            const bool opens = event == nlohmann::json::parse_event_t::object_start || event == nlohmann::json::parse_event_t::array_start;
            if (opens && depth >= kMaxJsonDepth) {
                throw IoError(path + ": not a JSON " + kind + " file (nested deeper than " + std::to_string(kMaxJsonDepth) + " levels)");
            }
            return true;
        });
    } catch (const nlohmann::json::exception& e) {
        // Parse errors and numbers out of range (1e999): one line, the library's words clipped.
        throw IoError(path + ": not a JSON " + kind + " file (" + std::string(e.what()).substr(0, 160) + ")");
    }
    if (!object.is_object()) throw ValueError(path + ": a " + kind + " file holds one JSON object of " + entries);
    return object;
}

std::vector<std::string> jobArguments(const std::string& path, const std::vector<std::string>& knownOptions,
    const std::vector<std::string>& flags, const std::vector<std::string>& givenOnCommandLine, bool positionalsGiven)
{
    const nlohmann::json job = readJsonObjectFile(path, "job", "option: value");

    std::vector<std::string> args, positionals(2);
    for (const auto& [key, value] : job.items()) {
        const std::string where = path + ": " + key;
        if (key == "input" || key == "output") {
            if (!value.is_string()) throw ValueError(where + ": expected a file name");
            positionals[key == "input" ? 0 : 1] = value.get<std::string>();
            continue;
        }
        if (key == "job") throw ValueError(where + ": a job file cannot name another job file");
        if (key == "volumes") { // --add-volume, --add-volume-transform and --add-volume-material, one entry a volume
            if (job.contains("add-volume") || job.contains("add-volume-transform") || job.contains("add-volume-material")) {
                throw ValueError(where + ": give 'volumes' or 'add-volume', not both");
            }
            if (contains(givenOnCommandLine, "add-volume")) continue;
            const std::vector<std::string> volumes = volumeArguments(value, where);
            args.insert(args.end(), volumes.begin(), volumes.end());
            continue;
        }
        if (!contains(knownOptions, key)) throw ValueError(path + ": unknown key '" + key + "' (keys are the long option names of vdb_ewa render --help)");
        if (contains(givenOnCommandLine, key)) continue;
        const std::vector<std::string> option = optionArguments(key, value, contains(flags, key), where);
        args.insert(args.end(), option.begin(), option.end());
    }
    if (!positionalsGiven) {
        if (positionals[0].empty() || positionals[1].empty()) {
            throw ValueError(path + ": give input and output, in the job file or on the command line");
        }
        args.insert(args.begin(), positionals.begin(), positionals.end());
    }
    return args;
}

std::vector<std::string> applyJobFile(const std::vector<std::string>& args, const CLI::App& render)
{
    // The option names, and which take no value.
    std::vector<std::string> known, flags;
    std::map<char, const CLI::Option*> shortNames;
    std::map<std::string, const CLI::Option*> longNames;
    for (const CLI::Option* opt : render.get_options()) {
        const bool flag = opt->get_expected_min() == 0;
        for (const std::string& n : opt->get_lnames()) {
            longNames[n] = opt;
            if (n == "help" || n == "job") continue;
            known.push_back(n);
            if (flag) flags.push_back(n);
        }
        for (const std::string& n : opt->get_snames()) shortNames[n[0]] = opt;
    }
    // Scan the command line: which options it gives, where --job is, how many positionals.
    std::vector<std::string> given, rest;
    std::string jobPath;
    int positionals = 0;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const CLI::Option* opt = nullptr;
        bool inlineValue = false;
        if (a.rfind("--", 0) == 0 && a.size() > 2) {
            const std::size_t eq = a.find('=');
            inlineValue = eq != std::string::npos;
            const auto it = longNames.find(a.substr(2, inlineValue ? eq - 2 : std::string::npos));
            if (it != longNames.end()) opt = it->second;
            if (opt && opt->get_lnames().front() == "job") {
                if (inlineValue) jobPath = a.substr(eq + 1);
                else if (i + 1 < args.size()) jobPath = args[++i];
                else throw ValueError("--job: expected a job file");
                continue;
            }
        } else if (a.size() == 2 && a[0] == '-' && shortNames.count(a[1])) {
            opt = shortNames[a[1]];
        } else if (a.empty() || a[0] != '-' || a == "-") {
            ++positionals;
        }
        rest.push_back(a);
        if (!opt) continue;
        given.insert(given.end(), opt->get_lnames().begin(), opt->get_lnames().end());
        if (opt->get_expected_min() > 0 && !inlineValue && i + 1 < args.size()) rest.push_back(args[++i]);
    }
    if (jobPath.empty()) return args;
    std::vector<std::string> out = jobArguments(jobPath, known, flags, given, positionals >= 2);
    out.insert(out.end(), rest.begin(), rest.end());
    out.push_back("--job=" + jobPath); // kept for the render: outputs must not name the job file
    return out;
}

} // namespace vdb_ewa::cli
