/// @file error_messages.cpp
#include "error_messages.h"

#include <regex>

namespace vdb_ewa::cli {

std::string errorLine(const std::string& message, const std::string& prefix)
{
    std::string line = prefix + message;
    for (char& c : line) {
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
    }
    constexpr std::size_t kMaxLine = 300;
    if (line.size() > kMaxLine) {
        std::size_t cut = kMaxLine - 3;
        while (cut > 0 && (static_cast<unsigned char>(line[cut]) & 0xc0) == 0x80) --cut;
        line = line.substr(0, cut) + "...";
    }
    return line;
}

std::string inOurWords(const CLI::ParseError& e)
{
    const std::string what = e.what();
    std::smatch m;
    if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
        const std::size_t colon = what.find(": ");
        return "unknown option or one argument too many: " + (colon == std::string::npos ? what : what.substr(colon + 2));
    }
    if (std::regex_match(what, m, std::regex("Could not convert: (\\S+) = (.*)"))) {
        return std::string(m[1]) + ": '" + std::string(m[2]) + "' is not a valid value";
    }
    if (std::regex_match(what, m, std::regex("(\\S+): \\d+ required \\S+ missing"))) return std::string(m[1]) + " needs a value";
    if (std::regex_match(what, m, std::regex("(input|output) is required"))) {
        return "no " + std::string(m[1]) + " given: vdb_ewa IN.vdb OUT.exr [options]";
    }
    if (what == "kind is required") return "no grid kind given: vdb_ewa make-grid KIND OUT.vdb";
    return what;
}

} // namespace vdb_ewa::cli
