/// @file farm_folder.cpp
#include "farm_folder.h"

#include "frame_sequence.h"

#include <vdb_ewa/error.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>

#include <unistd.h>

namespace vdb_ewa::cli {

namespace fs = std::filesystem;

std::string farmFolder(const std::string& jobPath, const std::string& given)
{
    if (!given.empty()) return fs::absolute(given).lexically_normal().string();
    const fs::path job = fs::absolute(jobPath).lexically_normal();
    return (job.parent_path() / (job.stem().string() + ".farm")).string();
}

std::string frameLogLine(int frame, FrameEntry::State state, const std::string& text, int exitCode)
{
    const std::string head = "vdb_ewa: frame " + std::to_string(frame);
    switch (state) {
    case FrameEntry::Done: return head + " done: " + text;
    case FrameEntry::Skipped: return head + " skipped: " + text;
    case FrameEntry::Failed: return head + " failed (exit " + std::to_string(exitCode) + "): " + text;
    case FrameEntry::Interrupted: break;
    }
    return head + " interrupted";
}

std::string taskLogFolder(const std::string& farm) { return (fs::path(farm) / "logs").string(); }

std::string taskLogPath(const std::string& farm, const std::string& id, int task)
{
    return (fs::path(taskLogFolder(farm)) / (id + "_" + std::to_string(task) + ".log")).string();
}

void recordSubmission(const std::string& farm, const Submission& s)
{
    const nlohmann::json record = {{"job_id", s.id}, {"frames", frameListText(s.frames)}, {"chunk", s.chunk}, {"submitted", s.submitted},
        {"folder", s.folder}, {"options", s.options}};
    const std::string path = (fs::path(farm) / (s.id + ".json")).string();
    const std::string temporary = path + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream out(temporary);
        out << record.dump(2) << "\n";
        if (!out.flush()) throw IoError(temporary + ": cannot write the submission's record");
    }
    std::error_code error;
    fs::rename(temporary, path, error);
    if (error) {
        fs::remove(temporary, error);
        throw IoError(path + ": cannot write the submission's record");
    }
}

std::vector<Submission> readSubmissions(const std::string& farm, std::vector<std::string>& warnings)
{
    std::vector<Submission> submissions;
    std::error_code error;
    for (const fs::directory_entry& entry : fs::directory_iterator(farm, error)) {
        const fs::path& p = entry.path();
        if (p.extension() != ".json") continue;
        try {
            std::ifstream in(p);
            const nlohmann::json record = nlohmann::json::parse(in);
            Submission s;
            s.id = record.at("job_id").get<std::string>();
            s.frames = parseFrameList(record.at("frames").get<std::string>());
            s.chunk = record.at("chunk").get<int>();
            s.submitted = record.value("submitted", "");
            s.folder = record.value("folder", "");
            s.options = record.value("options", "");
            if (s.chunk < 1) throw ValueError("chunk < 1");
            submissions.push_back(std::move(s));
        } catch (const std::exception&) {
            warnings.push_back(p.string() + ": not a submission record: skipped");
        }
    }
    // By time (job ids restart when a cluster is rebuilt or passes MaxJobId), then by id as a
    // number ("9" before "10").
    std::sort(submissions.begin(), submissions.end(), [](const Submission& a, const Submission& b) {
        if (a.submitted != b.submitted) return a.submitted < b.submitted;
        return a.id.size() != b.id.size() ? a.id.size() < b.id.size() : a.id < b.id;
    });
    return submissions;
}

TaskLog readTaskLog(const std::string& path)
{
    static const std::regex frameLine(R"(^vdb_ewa: frame (-?[0-9]+) (done|skipped|failed|interrupted)(?: \((exit [0-9]+)\))?:? ?(.*)$)");
    static const std::regex slurmEnd(R"(\*\*\* (?:JOB|STEP) \S+ ON \S+ CANCELLED AT \S+(?: DUE TO ([A-Z ]+?))? \*\*\*)");
    TaskLog log;
    std::ifstream in(path);
    log.exists = bool(in);
    std::string line;
    std::smatch m;
    while (std::getline(in, line)) {
        if (std::regex_search(line, m, frameLine)) {
            FrameEntry entry;
            const std::string state = m[2].str();
            entry.state = state == "done" ? FrameEntry::Done : state == "skipped" ? FrameEntry::Skipped
                        : state == "failed" ? FrameEntry::Failed : FrameEntry::Interrupted;
            if (entry.state == FrameEntry::Failed) entry.detail = m[3].str() + ": " + m[4].str();
            try {
                log.frames[parseFrameList(m[1].str()).front()] = entry;
            } catch (const ValueError&) { // not a frame number: not our line
            }
        } else if (std::regex_search(line, m, slurmEnd)) {
            std::string reason = m[1].matched ? m[1].str() : "";
            std::transform(reason.begin(), reason.end(), reason.begin(), [](unsigned char c) { return char(std::tolower(c)); });
            log.ended = "cancelled" + (reason.empty() ? "" : " due to " + reason);
        }
    }
    return log;
}

} // namespace vdb_ewa::cli
