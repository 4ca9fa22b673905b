/// @file option_values.cpp
#include "option_values.h"

#include <vdb_ewa/error.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>

namespace vdb_ewa::cli {

std::vector<double> parseNumbers(const std::string& option, const std::string& text)
{
    std::vector<double> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || end == item.c_str() || *end != '\0') {
            throw ValueError("--" + option + ": '" + text + "' is not a comma-separated list of numbers");
        }
        out.push_back(v);
    }
    if (out.empty()) throw ValueError("--" + option + ": missing value");
    return out;
}

double parseBytes(const std::string& option, const std::string& text)
{
    char* end = nullptr;
    double v = std::strtod(text.c_str(), &end);
    std::string suffix(end ? end : "");
    if (!suffix.empty() && (suffix.back() == 'B' || suffix.back() == 'b')) suffix.pop_back();
    const std::string units = "KMGT";
    const std::size_t u = suffix.size() == 1 ? units.find(char(std::toupper(static_cast<unsigned char>(suffix[0])))) : std::string::npos;
    if (text.empty() || end == text.c_str() || (!suffix.empty() && u == std::string::npos) || !std::isfinite(v) || v < 0.0) {
        throw ValueError("--" + option + ": '" + text + "' is not a size in bytes (a number with an optional K, M, G or T suffix)");
    }
    if (!suffix.empty()) v *= std::pow(1024.0, double(u + 1));
    return v;
}

std::string fmt(double v)
{
    std::ostringstream s;
    s << std::setprecision(6) << v;
    return s.str();
}

std::string fmt3(const Vec3d& v) { return fmt(v.x) + "," + fmt(v.y) + "," + fmt(v.z); }

double parseImageLod(const std::string& text)
{
    if (text == "off") return 0.0;
    const std::vector<double> v = parseNumbers("image-lod", text);
    if (v.size() != 1) throw ValueError("--image-lod: expected off or a number of samples, got '" + text + "'");
    return v[0];
}

std::string imageLodName(double samples) { return samples == 0.0 ? "off" : fmt(samples); }

Vec3d parseVec3(const std::string& option, const std::string& text, bool allowBroadcast)
{
    const std::vector<double> v = parseNumbers(option, text);
    if (v.size() == 1 && allowBroadcast) return Vec3d(v[0]);
    if (v.size() != 3) {
        throw ValueError("--" + option + ": expected X,Y,Z" + std::string(allowBroadcast ? " or one number" : "") +
                         ", got '" + text + "'");
    }
    return {v[0], v[1], v[2]};
}

void parseResolution(const std::string& text, int& width, int& height)
{
    const std::size_t sep = text.find_first_of("x,");
    char* end = nullptr;
    const long w = std::strtol(text.c_str(), &end, 10);
    const bool okW = sep != std::string::npos && end == text.c_str() + sep;
    const std::string rest = sep == std::string::npos ? "" : text.substr(sep + 1);
    const long h = std::strtol(rest.c_str(), &end, 10);
    const bool okH = !rest.empty() && *end == '\0';
    if (!okW || !okH || w < 1 || h < 1 || w > 65536 || h > 65536) {
        throw ValueError("--res: expected WxH with 1 <= W, H <= 65536, got '" + text + "'");
    }
    width = int(w);
    height = int(h);
}

std::vector<std::string> normalizeSingleDashOptions(const std::vector<std::string>& args,
    const std::set<std::string>& longNames)
{
    std::vector<std::string> out;
    out.reserve(args.size());
    for (const std::string& a : args) {
        if (a.size() > 2 && a[0] == '-' && a[1] != '-' && longNames.count(a.substr(1))) {
            out.push_back("-" + a);
        } else {
            out.push_back(a);
        }
    }
    return out;
}

} // namespace vdb_ewa::cli
