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

    void validate() const override { request(renderJob()); }

    int run() override
    {
        const RenderJob job = renderJob();
        SbatchRequest r = request(job);
        if (r.frames.empty()) {
            if (!mParsable) std::cout << "vdb_ewa: " << mJob << ": every frame's output exists: nothing to submit\n";
            return kExitOk;
        }
        if (mDryRun) {
            std::cout << sbatchScript(r);
            return kExitOk;
        }
        std::error_code error;
        fs::create_directories(fs::path(r.logPattern).parent_path(), error);
        if (error) throw IoError(farm() + ": cannot create the farm folder (" + error.message() + ")");
        const std::string script = (fs::path(farm()) / ("submit" + std::to_string(::getpid()) + ".sbatch")).string();
        {
            std::ofstream out(script);
            out << sbatchScript(r);
            if (!out.flush()) throw IoError(script + ": cannot write the batch script");
        }
        const ProgramResult sbatch = runProgram(mSbatch, {"--parsable", script});
        const std::string id = sbatch.out.substr(0, sbatch.out.find_first_of(";\n"));
        if (sbatch.exitCode != 0 || !std::regex_match(id, std::regex("[0-9]+"))) {
            fs::remove(script, error);
            std::string why = sbatch.failure.empty() ? sbatch.err.substr(0, sbatch.err.find('\n')) : sbatch.failure;
            if (why.empty()) why = "exit " + std::to_string(sbatch.exitCode) + ", printed '" + sbatch.out.substr(0, 60) + "'";
            throw std::runtime_error(mSbatch + ": the submission failed: " + why +
                                     (sbatch.failure == "not found" ? " (install Slurm's client, slurm-client, or give --sbatch)" : ""));
        }
        fs::rename(script, fs::path(farm()) / (id + ".sbatch"), error);
        recordSubmission(farm(), {id, r.frames, r.chunk, localTime()});
        if (mParsable) {
            std::cout << id << "\n";
        } else {
            const int tasks = chunkCount(r.frames.size(), r.chunk);
            std::cout << "vdb_ewa: submitted job " << id << ": " << counted(tasks, "task") << " of " << counted(r.chunk, "frame")
                      << " (frames " << frameListText(r.frames) << "); logs " << (fs::path(farm()) / "logs" / (id + "_*.log")).string()
                      << "; progress: vdb_ewa status " << shellQuoted(mJob) << "\n";
        }
        return kExitOk;
    }

private:
    static std::string localTime()
    {
        const std::time_t now = std::time(nullptr);
        std::tm local{};
        localtime_r(&now, &local);
        char text[32];
        std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &local);
        return text;
    }

    std::string farm() const { return mFarm.empty() ? defaultFarmFolder(mJob) : fs::absolute(mFarm).lexically_normal().string(); }

    /// The job as each task will parse it: a broken job fails here, not on the farm.
    RenderJob renderJob() const
    {
        std::vector<std::string> args{"--job", mJob};
        if (!mFrames.empty()) args.insert(args.end(), {"--frames", mFrames});
        const RenderJob job = renderJobOf(args);
        if (!job.sequence) throw ValueError("submit: " + mJob + " gives no frames: give --frames or a \"frames\" key");
        // Every task would fail on it (the render does not make folders, as vdb_render does not).
        const fs::path folder = fs::absolute(job.pathOf(job.output, job.frames.front())).parent_path();
        if (!fs::is_directory(folder)) throw IoError(job.pathOf(job.output, job.frames.front()) + ": folder '" + folder.string() + "' does not exist");
        return job;
    }

    SbatchRequest request(const RenderJob& job) const
    {
        static const std::regex memory("[0-9]+[KMGTkmgt]?"), time("[0-9]+(-[0-9]+)?(:[0-9]+){0,2}"), word("[A-Za-z0-9_.,+-]+");
        if (!mMemory.empty() && !std::regex_match(mMemory, memory)) throw ValueError("--mem: '" + mMemory + "' is not Slurm's memory size (4096, 4G, 500M)");
        if (!mTime.empty() && !std::regex_match(mTime, time)) throw ValueError("--time: '" + mTime + "' is not Slurm's time (30, 1:30:00, 2-00:00:00)");
        if (!mPartition.empty() && !std::regex_match(mPartition, word)) throw ValueError("--partition: '" + mPartition + "' is not a partition name");
        for (const std::string& e : mExtra) {
            if (e.rfind("-", 0) != 0) throw ValueError("--sbatch-option: '" + e + "' is not an option (--account=fx)");
        }
        SbatchRequest r;
        std::error_code error;
        r.program = fs::read_symlink("/proc/self/exe", error).string();
        if (error) throw std::runtime_error("submit: cannot find the vdb_ewa program (/proc/self/exe)");
        r.jobFile = fs::absolute(mJob).lexically_normal().string();
        r.workingFolder = fs::current_path().string();
        r.logPattern = taskLogPattern(farm());
        r.name = mName.empty() ? "vdb_ewa:" + fs::path(mJob).stem().string() : mName;
        r.partition = mPartition;
        r.memory = mMemory;
        r.time = mTime;
        r.cpus = mCpus;
        r.chunk = mChunk;
        r.maxRunning = mMaxRunning;
        r.extra = mExtra;
        r.skipExisting = mSkipExisting || job.skipExisting;
        for (const int f : job.frames) {
            if (!r.skipExisting || !job.done(f)) r.frames.push_back(f);
        }
        r.commandLine = "vdb_ewa submit " + shellQuoted(mJob) + (mFrames.empty() ? "" : " --frames " + shellQuoted(mFrames)) +
                        " --chunk " + std::to_string(mChunk) + (r.skipExisting ? " --skip-existing" : "");
        if (!r.frames.empty()) sbatchScript(r); // the values fit in the script
        return r;
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
