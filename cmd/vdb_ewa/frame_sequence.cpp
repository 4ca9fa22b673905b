/// @file frame_sequence.cpp
#include "frame_sequence.h"

#include <vdb_ewa/error.h>

#include <algorithm>
#include <cstdlib>
#include <regex>
#include <set>

namespace vdb_ewa::cli {
namespace {

/// One `####` run or one `%d` / `%0Nd`.
const std::regex kPattern(R"(#+|%(0[1-9][0-9]?)?d)");

int parseInt(const std::string& text, const std::string& item)
{
    try {
        std::size_t used = 0;
        const long v = std::stol(text, &used);
        if (used != text.size() || v < -1000000000L || v > 1000000000L) throw std::out_of_range(text);
        return int(v);
    } catch (const std::exception&) {
        throw ValueError("--frames: '" + item + "' is not a frame, range A-B or stepped range A-BxS");
    }
}

} // namespace

std::vector<int> parseFrameList(const std::string& spec)
{
    static const std::regex item(R"((-?[0-9]+)(?:-(-?[0-9]+)(?:x([0-9]+))?)?)");
    if (spec.empty()) throw ValueError("--frames: empty frame list");
    std::vector<int> frames;
    std::set<int> seen;
    std::size_t start = 0;
    while (start <= spec.size()) {
        const std::size_t comma = std::min(spec.find(',', start), spec.size());
        const std::string text = spec.substr(start, comma - start);
        std::smatch m;
        if (!std::regex_match(text, m, item)) {
            throw ValueError("--frames: '" + text + "' is not a frame, range A-B or stepped range A-BxS");
        }
        const int a = parseInt(m[1].str(), text);
        const int b = m[2].matched ? parseInt(m[2].str(), text) : a;
        const int step = m[3].matched ? parseInt(m[3].str(), text) : 1;
        if (b < a) throw ValueError("--frames: '" + text + "' ends before it starts");
        if (step < 1) throw ValueError("--frames: '" + text + "' needs a step of at least 1");
        if ((long(b) - long(a)) / step > 1000000) throw ValueError("--frames: '" + text + "' has more than a million frames");
        for (long f = a; f <= b; f += step) {
            if (seen.insert(int(f)).second) frames.push_back(int(f));
        }
        start = comma + 1;
    }
    return frames;
}

bool hasFramePattern(const std::string& path) { return std::regex_search(path, kPattern); }

std::string framePath(const std::string& path, int frame)
{
    std::smatch m;
    if (!std::regex_search(path, m, kPattern)) return path;
    const std::string rest = m.suffix().str();
    if (std::regex_search(rest, kPattern)) throw ValueError(path + ": more than one frame pattern (#### or %04d)");
    const std::string token = m.str();
    std::size_t width = 1;
    if (token[0] == '#') width = token.size();
    else if (token.size() > 2) width = std::size_t(std::atoi(token.c_str() + 1)); // %0Nd
    std::string digits = std::to_string(std::abs(long(frame)));
    if (digits.size() < width) digits.insert(0, width - digits.size(), '0');
    return m.prefix().str() + (frame < 0 ? "-" : "") + digits + rest;
}

int chunkCount(std::size_t frameCount, int chunk)
{
    if (chunk < 1) throw ValueError("--chunk: " + std::to_string(chunk) + " frames a task: give at least 1");
    return int((frameCount + std::size_t(chunk) - 1) / std::size_t(chunk));
}

std::vector<int> frameChunk(const std::vector<int>& frames, int chunk, int task)
{
    const int chunks = chunkCount(frames.size(), chunk);
    if (task < 0 || task >= chunks) {
        throw ValueError("--task " + std::to_string(task) + ": the " + std::to_string(frames.size()) + " frames make " + std::to_string(chunks) +
                         " chunk" + (chunks == 1 ? "" : "s") + " of " + std::to_string(chunk) + " (tasks 0-" + std::to_string(chunks - 1) + ")");
    }
    const std::size_t begin = std::size_t(task) * std::size_t(chunk);
    return {frames.begin() + long(begin), frames.begin() + long(std::min(frames.size(), begin + std::size_t(chunk)))};
}

std::string frameListText(const std::vector<int>& frames)
{
    std::string text;
    for (std::size_t i = 0; i < frames.size();) {
        std::size_t j = i;
        while (j + 1 < frames.size() && long(frames[j + 1]) == long(frames[j]) + 1) ++j;
        text += (text.empty() ? "" : ",") + std::to_string(frames[i]) + (j > i ? "-" + std::to_string(frames[j]) : "");
        i = j + 1;
    }
    return text;
}

} // namespace vdb_ewa::cli
