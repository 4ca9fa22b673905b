/// @file submit_command.cpp
/// @brief `vdb_ewa submit shot.json --frames 1-240 --chunk 4`: the shot as a Slurm job array
///        through sbatch, one task per chunk of frames (docs/farm.md).
#include "commands.h"
#include "exit_codes.h"
#include "farm_folder.h"
#include "frame_sequence.h"
#include "progress_report.h"
#include "run_program.h"
#include "sbatch_script.h"

#include <vdb_ewa/vdb_ewa.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <set>

#include <unistd.h>

namespace vdb_ewa::cli {
namespace {

namespace fs = std::filesystem;

class SubmitCommand : public Command
{
public:
    explicit SubmitCommand(CLI::App& app)
    {
        mApp = app.add_subcommand("submit", "Submit a job file's frames to Slurm as a job array, one task per chunk of frames (docs/farm.md)");
        mApp->add_option("job", mJob, "the job file (vdb_ewa render --job): input, output and options")->required();
        mApp->add_option("--frames", mFrames, "the frames (as render's --frames) (default: the job file's frames)");
        mApp->add_option("--chunk", mChunk, "frames a task, in [1, 1000000]; task I renders frames [I*N, (I+1)*N) (default: 1)")
            ->check(CLI::Range(1, 1000000));
        mApp->add_option("--partition", mPartition, "Slurm partition (default: the cluster's default partition)");
        mApp->add_option("--mem", mMemory,
            "memory a task, Slurm's syntax: a number of MB or with a K, M, G or T suffix; the render's frame budget is 3/4 of "
            "it (default: the cluster's default)");
        mApp->add_option("--cpus", mCpus, "CPUs a task, in [1, 4096]; the render uses as many threads (default: the cluster's default, 1 on most)")
            ->check(CLI::Range(1, 4096));
        mApp->add_option("--time", mTime, "time limit a task, Slurm's syntax: minutes, MM:SS, HH:MM:SS or D-HH[:MM[:SS]] (default: the partition's)");
        mApp->add_option("--name", mName, "the job's name in the queue (default: vdb_ewa:<job file stem>)");
        mApp->add_option("--max-running", mMaxRunning, "at most this many tasks at once, in [1, 1000000] (default: no limit)")
            ->check(CLI::Range(1, 1000000));
        mApp->add_option("--sbatch-option", mExtra,
            "one more sbatch option for the script, repeatable: --sbatch-option=--account=fx --sbatch-option=--qos=high")
            ->expected(1)
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        mApp->add_option("--farm-dir", mFarm,
            "where the scripts, the submission records and the tasks' logs go (default: <job file folder>/<stem>.farm)");
        mApp->add_flag("--skip-existing", mSkipExisting,
            "submit only the frames whose output (and --preview) are missing, and the tasks skip any that exist when they run");
        mApp->add_option("--sbatch", mSbatch, "the sbatch program (default: sbatch, from PATH)");
        mApp->add_flag("--dry-run", mDryRun, "print the script; submit nothing and write nothing");
        mApp->add_flag("--parsable", mParsable, "print only the job id");
    }

    CLI::App* subcommand() const override { return mApp; }

    void validate() const override { request(renderJob(), 0); }

    int run() override
    {
        const RenderJob job = renderJob();
        const std::time_t now = std::time(nullptr);
        const SbatchRequest r = request(job, now);
        if (r.frames.empty()) {
            if (!mParsable) std::cout << "vdb_ewa: " << mJob << ": every frame's output exists: nothing to submit\n";
            return kExitOk;
        }
        if (mDryRun) {
            std::cout << sbatchScript(r);
            return kExitOk;
        }
        const std::string farm = farmFolder(mJob, mFarm);
        std::error_code error;
        fs::create_directories(r.logFolder, error);
        if (error) throw IoError(farm + ": cannot create the farm folder (" + error.message() + ")");
        const std::string script = (fs::path(farm) / ("submit" + std::to_string(::getpid()) + ".sbatch")).string();
        {
            std::ofstream out(script);
            out << sbatchScript(r);
            if (!out.flush()) throw IoError(script + ": cannot write the batch script");
        }
        const ProgramResult sbatch = runProgram(mSbatch, {"--parsable", script});
        const std::string id = sbatch.out.substr(0, sbatch.out.find_first_of(";\n")); // "id" or "id;cluster"
        if (sbatch.exitCode != 0 || !std::regex_match(id, std::regex("[0-9]+"))) {
            fs::remove(script, error);
            const std::string why = sbatch.exitCode == 0 ? "it printed '" + sbatch.out.substr(0, 60) + "', not a job id" : sbatch.why(mSbatch);
            const bool array = why.find("array") != std::string::npos;
            throw std::runtime_error(mSbatch + ": the submission failed: " + why +
                (sbatch.failure == "not found" ? " (install Slurm's client, slurm-client, or give --sbatch)"
                 : array ? " (" + std::to_string(chunkCount(r.frames.size(), r.chunk)) + " tasks: over the cluster's MaxArraySize? raise --chunk)" : ""));
        }
        fs::rename(script, fs::path(farm) / (id + ".sbatch"), error);
        try {
            recordSubmission(farm, {id, r.frames, r.chunk, utcTime(now), r.workingFolder, resubmitOptions()});
        } catch (const IoError& e) {
            throw IoError("job " + id + " was submitted, but " + e.what() + ": vdb_ewa status cannot follow it");
        }
        if (mParsable) {
            std::cout << id << "\n";
        } else {
            const int tasks = chunkCount(r.frames.size(), r.chunk);
            std::cout << "vdb_ewa: submitted job " << id << ": " << counted(tasks, "task") << " of " << counted(r.chunk, "frame")
                      << " (frames " << frameListText(r.frames) << "); logs " << (fs::path(r.logFolder) / (id + "_*.log")).string()
                      << "; progress: vdb_ewa status " << shellQuoted(mJob) << (mFarm.empty() ? "" : " --farm-dir " + shellQuoted(mFarm)) << "\n";
        }
        return kExitOk;
    }

private:
    static std::string utcTime(std::time_t t)
    {
        std::tm utc{};
        gmtime_r(&t, &utc);
        char text[32];
        std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
        return text;
    }

    RenderJob renderJob() const
    {
        const RenderJob job = renderJobOfFile(mJob, mFrames);
        if (!job.sequence) throw ValueError("submit: " + mJob + " gives no frames: give --frames or a \"frames\" key");
        return job;
    }

    /// The sbatch request for @a job, submitted at @a now; the job checked as each task will
    /// parse it, so a broken job fails here, not on the farm.
    SbatchRequest request(const RenderJob& job, std::time_t now) const
    {
        static const std::regex memory("[0-9]+[KMGTkmgt]?"), time("[0-9]+(-[0-9]+)?(:[0-9]+){0,2}|UNLIMITED|INFINITE|unlimited|infinite"),
            word("[A-Za-z0-9_.,+-]+");
        if (!mMemory.empty() && !std::regex_match(mMemory, memory)) throw ValueError("--mem: '" + mMemory + "' is not Slurm's memory size (4096, 4G, 500M)");
        if (!mTime.empty() && !std::regex_match(mTime, time)) throw ValueError("--time: '" + mTime + "' is not Slurm's time (30, 1:30:00, 2-00:00:00, UNLIMITED)");
        if (!mPartition.empty() && !std::regex_match(mPartition, word)) throw ValueError("--partition: '" + mPartition + "' is not a partition name");
        SbatchRequest r;
        std::error_code error;
        r.program = fs::read_symlink("/proc/self/exe", error).string();
        if (error) throw std::runtime_error("submit: cannot find the vdb_ewa program (/proc/self/exe)");
        r.jobFile = fs::absolute(mJob).lexically_normal().string();
        r.workingFolder = fs::current_path().string();
        r.logFolder = taskLogFolder(farmFolder(mJob, mFarm));
        r.name = mName.empty() ? "vdb_ewa:" + fs::path(mJob).stem().string() : mName;
        r.partition = mPartition;
        r.memory = mMemory;
        r.time = mTime;
        r.cpus = mCpus;
        r.chunk = mChunk;
        r.maxRunning = mMaxRunning;
        r.extra = mExtra;
        r.submitted = (long long)now;
        r.skipExisting = mSkipExisting || job.skipExisting;
        std::set<std::string> folders;
        for (const int f : job.frames) {
            if (r.skipExisting && job.done(f)) continue;
            r.frames.push_back(f);
            // Every task would fail on a missing output folder (the render makes none, as vdb_render makes none).
            for (const std::string& pattern : {job.output, job.preview}) {
                const std::string path = job.pathOf(pattern, f);
                if (path.empty()) continue;
                const std::string folder = fs::absolute(path).parent_path().string();
                if (folders.insert(folder).second && !fs::is_directory(folder)) throw IoError(path + ": folder '" + folder + "' does not exist");
            }
        }
        r.commandLine = "vdb_ewa submit " + shellQuoted(mJob) + (mFrames.empty() ? "" : " --frames " + shellQuoted(mFrames)) + resubmitOptions();
        if (!r.frames.empty()) sbatchScript(r); // the values fit in the script
        return r;
    }

    /// The options given, but the job, --frames and those of this one call (--dry-run,
    /// --parsable), as shell words: a resubmission of the missing frames repeats them.
    std::string resubmitOptions() const
    {
        std::string line;
        for (const CLI::Option* opt : mApp->get_options()) {
            if (opt->get_lnames().empty() || opt->count() == 0) continue;
            const std::string name = opt->get_lnames().front();
            if (name == "help" || name == "frames" || name == "dry-run" || name == "parsable") continue;
            if (opt->get_expected_min() == 0) {
                line += " --" + name; // a flag
                continue;
            }
            for (const std::string& given : opt->results()) {
                const std::string value = name == "farm-dir" ? farmFolder(mJob, mFarm) : given; // from any folder
                line += " --" + name + (value.rfind("-", 0) == 0 ? "=" : " ") + shellQuoted(value);
            }
        }
        return line;
    }

    CLI::App* mApp = nullptr;
    std::string mJob, mFrames, mPartition, mMemory, mTime, mName, mFarm, mSbatch = "sbatch";
    std::vector<std::string> mExtra;
    int mChunk = 1, mCpus = 0, mMaxRunning = 0;
    bool mSkipExisting = false, mDryRun = false, mParsable = false;
};

} // namespace

std::unique_ptr<Command> addSubmitCommand(CLI::App& app) { return std::make_unique<SubmitCommand>(app); }

} // namespace vdb_ewa::cli
