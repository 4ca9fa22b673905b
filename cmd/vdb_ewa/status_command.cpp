/// @file status_command.cpp
/// @brief `vdb_ewa status shot.json`: which frames of a job file are done, running, queued,
///        failed or missing, from the outputs, the farm folder's logs and Slurm's queue
///        (docs/farm.md).
#include "commands.h"
#include "exit_codes.h"
#include "farm_folder.h"
#include "frame_sequence.h"
#include "progress_report.h"
#include "run_program.h"
#include "sbatch_script.h"

#include <vdb_ewa/vdb_ewa.h>

#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

namespace vdb_ewa::cli {
namespace {

namespace fs = std::filesystem;

/// The latest submission of a frame: its task, the task's queue state and what its log says.
struct Attempt
{
    std::string job;
    int task = 0;
    std::string queueState; ///< squeue's; empty once the task has left the queue
    std::string logPath;
    std::optional<FrameEntry> entry;   ///< the log's last line on the frame; none: no line
    std::string ended;                 ///< the scheduler's reason for ending the task
    bool started = false;              ///< the task has a log
};

class StatusCommand : public Command
{
public:
    explicit StatusCommand(CLI::App& app)
    {
        mApp = app.add_subcommand("status",
            "List a job file's frames that are done, running, queued, failed or missing, from the outputs, the farm "
            "folder's logs and Slurm's queue; exit 0 when every frame is done, 1 when not (docs/farm.md)");
        mApp->add_option("job", mJob, "the job file (vdb_ewa render --job)")->required();
        mApp->add_option("--frames", mFrames, "the frames (as render's --frames) (default: the job file's frames)");
        mApp->add_option("--farm-dir", mFarm, "the farm folder of vdb_ewa submit (default: <job file folder>/<stem>.farm)");
        mApp->add_option("--squeue", mSqueue, "the squeue program; empty: do not ask the queue (default: squeue, from PATH)");
    }

    CLI::App* subcommand() const override { return mApp; }

    void validate() const override { renderJobOfFile(mJob, mFrames); }

    int run() override
    {
        const RenderJob job = renderJobOfFile(mJob, mFrames);
        const std::string farm = farmFolder(mJob, mFarm);
        std::vector<std::string> warnings;
        const std::vector<Submission> submissions = readSubmissions(farm, warnings);
        const std::map<std::string, std::string> queue = submissions.empty() ? std::map<std::string, std::string>{} : queueStates(submissions, warnings);
        // The job's relative paths are the tasks' (the latest submission's working folder).
        const std::string folder = submissions.empty() ? "" : submissions.back().folder;

        // Each frame's latest attempt, oldest submission first.
        std::map<int, Attempt> attempts;
        for (const Submission& s : submissions) {
            for (int task = 0, tasks = chunkCount(s.frames.size(), s.chunk); task < tasks; ++task) {
                const std::string logPath = taskLogPath(farm, s.id, task);
                const TaskLog log = readTaskLog(logPath);
                const auto state = queue.find(s.id + "_" + std::to_string(task));
                for (const int f : frameChunk(s.frames, s.chunk, task)) {
                    const auto entry = log.frames.find(f);
                    attempts[f] = {s.id, task, state == queue.end() ? "" : state->second, logPath,
                                   entry == log.frames.end() ? std::nullopt : std::optional<FrameEntry>(entry->second), log.ended, log.exists};
                }
            }
        }

        std::vector<int> done, running, queued, failed, unfinished;
        std::map<std::string, std::vector<int>> missing; // by reason
        std::vector<std::string> failures;
        for (const int f : job.frames) {
            const auto a = attempts.find(f);
            if (job.done(f, folder)) {
                done.push_back(f);
                continue;
            }
            unfinished.push_back(f);
            if (a == attempts.end()) {
                missing["never submitted"].push_back(f);
                continue;
            }
            const Attempt& at = a->second;
            const std::string where = "job " + at.job + " task " + std::to_string(at.task);
            const std::string& q = at.queueState;
            if (q == "RUNNING" || q == "COMPLETING" || q == "CONFIGURING" || q == "STAGE_OUT") {
                running.push_back(f);
            } else if (!q.empty()) { // PENDING, REQUEUED, SUSPENDED, ...
                queued.push_back(f);
            } else if (at.entry && at.entry->state == FrameEntry::Failed) {
                failed.push_back(f);
                failures.push_back("frame " + std::to_string(f) + ": " + at.entry->detail + " (" + where + ", " + at.logPath + ")");
            } else if (at.entry && at.entry->state != FrameEntry::Interrupted) {
                missing[where + " wrote it, but the output is gone"].push_back(f);
            } else {
                const std::string why = !at.ended.empty() ? at.ended : at.entry ? "interrupted" : at.started ? "ended before it" : "never started";
                missing[where + " " + why].push_back(f);
            }
        }
        for (const std::string& w : warnings) std::cerr << "vdb_ewa: warning: " << w << "\n";
        std::size_t missingCount = 0;
        for (const auto& [why, frames] : missing) missingCount += frames.size();
        std::cout << mJob << ": " << counted(std::int64_t(job.frames.size()), "frame") << " (" << frameListText(job.frames) << "): " << done.size()
                  << " done, " << running.size() << " running, " << queued.size() << " queued, " << failed.size() << " failed, " << missingCount
                  << " missing\n";
        if (!running.empty()) std::cout << "running: " << frameListText(running) << "\n";
        if (!queued.empty()) std::cout << "queued: " << frameListText(queued) << "\n";
        for (const std::string& f : failures) std::cout << "failed: " << f << "\n";
        for (const auto& [why, frames] : missing) std::cout << "missing: " << frameListText(frames) << " (" << why << ")\n";
        if (unfinished.empty()) return kExitOk;
        if (running.empty() && queued.empty()) { // the latest submission's options, for the frames left
            std::string options = submissions.empty() ? (mFarm.empty() ? "" : " --farm-dir " + shellQuoted(farm)) : submissions.back().options;
            if (options.find(" --skip-existing") == std::string::npos) options += " --skip-existing";
            std::cout << "to finish: vdb_ewa submit " << shellQuoted(mJob) << " --frames " << frameListText(unfinished) << options << "\n";
        }
        return kExitIncomplete;
    }

private:
    /// squeue's state of each array task of @a submissions ("15_2" -> "RUNNING"); empty, with a
    /// warning, where squeue cannot say.
    std::map<std::string, std::string> queueStates(const std::vector<Submission>& submissions, std::vector<std::string>& warnings) const
    {
        std::map<std::string, std::string> states;
        if (mSqueue.empty()) return states;
        std::string ids;
        for (const Submission& s : submissions) ids += (ids.empty() ? "" : ",") + s.id;
        const ProgramResult r = runProgram(mSqueue, {"--noheader", "--array", "--format=%i %T", "--jobs=" + ids}, 30.0);
        if (r.exitCode != 0 && r.err.find("Invalid job id") != std::string::npos) return states; // all have left the queue
        if (r.exitCode != 0) {
            warnings.push_back(mSqueue + ": " + r.why(mSqueue) + ": the queue is unknown, so running and queued frames show as missing");
            return states;
        }
        std::istringstream lines(r.out);
        std::string id, state;
        while (lines >> id >> state) states[id] = state;
        return states;
    }

    CLI::App* mApp = nullptr;
    std::string mJob, mFrames, mFarm, mSqueue = "squeue";
};

} // namespace

std::unique_ptr<Command> addStatusCommand(CLI::App& app) { return std::make_unique<StatusCommand>(app); }

} // namespace vdb_ewa::cli
