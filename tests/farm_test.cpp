/// @file farm_test.cpp
/// @brief Render farms (docs/farm.md): array tasks' chunks, the CPUs and memory a task was
///        granted, `vdb_ewa submit` against a stand-in sbatch, `vdb_ewa status` from logs and a
///        stand-in squeue. The real Slurm is tests/slurm/test_slurm.py.
#include "cli_fixtures.h"

#include "../cmd/vdb_ewa/farm_folder.h"
#include "../cmd/vdb_ewa/frame_sequence.h"
#include "../cmd/vdb_ewa/granted_resources.h"
#include "../cmd/vdb_ewa/sbatch_script.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <ctime>

using namespace vdb_ewa;
using namespace vdb_ewa::test;
using namespace vdb_ewa::cli;

namespace fs = std::filesystem;

namespace {

/// Run the CLI in @a dir's folder with the environment assignments @a env ("A=1 B=2").
CliRun runCliWith(const TempDir& dir, const std::string& env, const std::string& args)
{
    return runCli(dir, args, "", "cd " + dir.file("") + " && env -u SLURM_ARRAY_TASK_ID -u SLURM_CPUS_PER_TASK -u SLURM_JOB_CPUS_PER_NODE "
                                  "-u SLURM_MEM_PER_NODE -u SLURM_MEM_PER_CPU " + env + " ");
}

void writeFile(const std::string& path, const std::string& text, bool executable = false)
{
    std::ofstream(path) << text;
    if (executable) fs::permissions(path, fs::perms::owner_all, fs::perm_options::add);
}

/// A shot of 6 frames (frame 3 without its grid) and its job file, in the fixture's folder.
class Farm : public ::testing::Test
{
protected:
    void SetUp() override
    {
        for (int f : {1, 2, 4, 5, 6}) writeSampleGrid(SampleGrid::Cloud, mDir.file("in." + std::to_string(f) + ".vdb"), 0.08);
        fs::create_directory(mDir.file("out"));
        writeFile(mJob, R"({"input": "in.#.vdb", "output": "out/o.#.exr", "frames": "1-6", "res": "32x24", "translate": [0, 0, 5], "quality": "draft"})");
    }

    /// The frames whose "frame N done" lines @a out holds, in order.
    static std::vector<int> doneFrames(const std::string& out)
    {
        std::vector<int> frames;
        static const std::regex line(R"(vdb_ewa: frame (\d+) done: )");
        for (auto it = std::sregex_iterator(out.begin(), out.end(), line); it != std::sregex_iterator(); ++it) frames.push_back(std::stoi((*it)[1]));
        return frames;
    }

    TempDir mDir;
    std::string mJob = mDir.file("shot.json");
};

} // namespace

TEST(FrameChunks, CutTheFramesInOrderAndWriteThemBackAsAList)
{
    const std::vector<int> frames = parseFrameList("1-10");
    EXPECT_EQ(chunkCount(frames.size(), 4), 3);
    EXPECT_EQ(frameChunk(frames, 4, 0), (std::vector<int>{1, 2, 3, 4}));
    EXPECT_EQ(frameChunk(frames, 4, 2), (std::vector<int>{9, 10}));
    EXPECT_EQ(frameChunk(parseFrameList("20,5,7-8"), 2, 1), (std::vector<int>{7, 8})) << "the list's order, not sorted";
    EXPECT_THROW(frameChunk(frames, 4, 3), ValueError);
    EXPECT_THROW(frameChunk(frames, 4, -1), ValueError);
    EXPECT_THROW(frameChunk(frames, 0, 0), ValueError);
    EXPECT_EQ(frameListText({1, 2, 3, 4, 9, 11, 12}), "1-4,9,11-12");
    EXPECT_EQ(frameListText({-3, -2, -1, 0, 5, 4}), "-3-0,5,4");
    // Any list reads back as itself, in its order.
    std::mt19937 random(7);
    for (int trial = 0; trial < 200; ++trial) {
        std::vector<int> list;
        for (int f = -20; f < 40; ++f) {
            if (random() % 3) list.push_back(f);
        }
        std::shuffle(list.begin(), list.begin() + long(list.size() / 3), random);
        if (list.empty()) continue;
        EXPECT_EQ(parseFrameList(frameListText(list)), list) << frameListText(list);
    }
}

TEST(GrantedResources, TheSmallestGrantOfSlurmAndTheCgroupWins)
{
    TempDir dir;
    std::map<std::string, std::string> env;
    ResourceSources sources;
    sources.getenv = [&](const char* name) { const auto it = env.find(name); return it == env.end() ? nullptr : it->second.c_str(); };
    sources.cgroupRoot = dir.file("cgroup");
    sources.procSelfCgroup = dir.file("proc_self_cgroup");

    // Nothing granted: no Slurm, no cgroup files.
    GrantedResources g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 0);
    EXPECT_EQ(g.memoryBytes, 0.0);

    // Slurm alone (the affinity is every CPU online: no grant).
    sources.affinityCpus = [] { return 8; };
    sources.onlineCpus = [] { return 8; };
    env = {{"SLURM_CPUS_PER_TASK", "3"}, {"SLURM_MEM_PER_NODE", "500"}, {"SLURM_JOB_CPUS_PER_NODE", "8"}};
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 3);
    EXPECT_EQ(g.cpusFrom, "SLURM_CPUS_PER_TASK=3");
    EXPECT_EQ(g.memoryBytes, 500.0 * 1024 * 1024);
    env = {{"SLURM_JOB_CPUS_PER_NODE", "2(x3)"}, {"SLURM_MEM_PER_CPU", "100"}};
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 2);
    EXPECT_EQ(g.memoryBytes, 200.0 * 1024 * 1024) << "per CPU, times the CPUs";
    env = {{"SLURM_CPUS_PER_TASK", "1e12"}};
    EXPECT_EQ(grantedResources(sources).cpus, 65536) << "clamped";
    // A cpuset (Slurm's task/affinity or task/cgroup binding) shows as the affinity.
    sources.affinityCpus = [] { return 3; };
    env.clear();
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 3);
    EXPECT_EQ(g.cpusFrom, "the process's CPU affinity (3 of 8 CPUs)");
    sources.affinityCpus = [] { return 8; };
    env = {{"SLURM_CPUS_PER_TASK", "two"}, {"SLURM_MEM_PER_NODE", "-5"}};
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 0) << "malformed values are no grant";
    EXPECT_EQ(g.memoryBytes, 0.0);

    // cgroup v2: the process's group and its parents; the smaller limit wins, "max" is none.
    writeFile(sources.procSelfCgroup, "0::/slurm/job_7\n");
    fs::create_directories(dir.file("cgroup/slurm/job_7"));
    writeFile(dir.file("cgroup/slurm/job_7/cpu.max"), "150000 100000\n");
    writeFile(dir.file("cgroup/slurm/job_7/memory.max"), "max\n");
    writeFile(dir.file("cgroup/slurm/memory.max"), "1073741824\n");
    env = {{"SLURM_CPUS_PER_TASK", "4"}, {"SLURM_MEM_PER_NODE", "2048"}};
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 2) << "1.5 CPUs of quota, rounded up, under Slurm's 4";
    EXPECT_NE(g.cpusFrom.find("cgroup"), std::string::npos) << g.cpusFrom;
    EXPECT_EQ(g.memoryBytes, 1073741824.0) << "the parent's limit";
    env = {{"SLURM_CPUS_PER_TASK", "4"}, {"SLURM_MEM_PER_CPU", "100"}};
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 2) << "the quota";
    EXPECT_EQ(g.memoryBytes, 400.0 * 1024 * 1024) << "per CPU of Slurm's 4, not of the quota's 2";
    // What --threads 0 and --max-memory 0 become; explicit values stay.
    GrantedSettings settings = grantedSettings(0, 0.0, g);
    EXPECT_EQ(settings.threads, 2);
    EXPECT_EQ(settings.maxMemory, 300.0 * 1024 * 1024);
    settings = grantedSettings(5, 1e9, g);
    EXPECT_EQ(settings.threads, 5);
    EXPECT_EQ(settings.maxMemory, 1e9);
    EXPECT_EQ(settings.text, "");
    EXPECT_EQ(grantedSettings(0, 0.0, GrantedResources{0, "", 10.0 * 1024 * 1024, "x"}).maxMemory, 64.0 * 1024 * 1024) << "at least 64 MB";
    EXPECT_EQ(grantedSettings(0, 0.0, GrantedResources{0, "", 1e30, "x"}).maxMemory, 1e18) << "within --max-memory's range";

    // cgroup v1: per controller; -1 and 2^63 are none.
    writeFile(sources.procSelfCgroup, "4:memory:/docker/abc\n3:cpu,cpuacct:/docker/abc\n");
    fs::create_directories(dir.file("cgroup/memory/docker/abc"));
    fs::create_directories(dir.file("cgroup/cpu,cpuacct/docker/abc"));
    writeFile(dir.file("cgroup/memory/docker/abc/memory.limit_in_bytes"), "9223372036854771712\n");
    writeFile(dir.file("cgroup/memory/memory.limit_in_bytes"), "268435456\n");
    writeFile(dir.file("cgroup/cpu,cpuacct/docker/abc/cpu.cfs_quota_us"), "-1\n");
    writeFile(dir.file("cgroup/cpu,cpuacct/docker/abc/cpu.cfs_period_us"), "100000\n");
    env.clear();
    g = grantedResources(sources);
    EXPECT_EQ(g.cpus, 0);
    EXPECT_EQ(g.memoryBytes, 268435456.0);
    writeFile(dir.file("cgroup/cpu,cpuacct/docker/abc/cpu.cfs_quota_us"), "300000\n");
    EXPECT_EQ(grantedResources(sources).cpus, 3);
}

TEST_F(Farm, AnArrayTaskRendersItsChunkWithTheGrantedThreadsAndMemory)
{
    const CliRun task = runCliWith(mDir, "SLURM_ARRAY_TASK_ID=2 SLURM_CPUS_PER_TASK=1 SLURM_MEM_PER_NODE=500", "render --job shot.json --chunk 2 -v");
    ASSERT_EQ(task.code, 0) << task.err;
    EXPECT_NE(task.out.find("vdb_ewa: task 2: frames 5-6; 1 thread (SLURM_CPUS_PER_TASK=1), a frame's memory budget 375 MB "
                            "(3/4 of SLURM_MEM_PER_NODE=500 MB)\n"), std::string::npos) << task.out;
    EXPECT_EQ(doneFrames(task.out), (std::vector<int>{5, 6}));
    EXPECT_NE(task.out.find("--threads 1"), std::string::npos) << "-v's settings: " << task.out;
    for (int f = 1; f <= 6; ++f) EXPECT_EQ(fs::exists(mDir.file("out/o." + std::to_string(f) + ".exr")), f >= 5) << f;
    // Each frame's line: its time and its own peak memory.
    EXPECT_TRUE(std::regex_search(task.out, std::regex(R"(vdb_ewa: frame 6 done: out/o\.6\.exr \(\d+\.\d\d s, peak \d+ MB\)\n)"))) << task.out;

    // --task wins over the environment; a task past the last chunk is an argument error.
    EXPECT_EQ(doneFrames(runCliWith(mDir, "SLURM_ARRAY_TASK_ID=2", "render --job shot.json --chunk 4 --task 0").out), (std::vector<int>{1, 2, 4}));
    const CliRun past = runCliWith(mDir, "SLURM_ARRAY_TASK_ID=3", "render --job shot.json --chunk 2");
    EXPECT_EQ(past.code, 2);
    EXPECT_NE(past.err.find("--task 3: the 6 frames make 3 chunks of 2 (tasks 0-2)"), std::string::npos) << past.err;
    const CliRun none = runCliWith(mDir, "", "render --job shot.json --chunk 2");
    EXPECT_EQ(none.code, 2);
    EXPECT_NE(none.err.find("--chunk: no task index"), std::string::npos) << none.err;
    EXPECT_EQ(runCliWith(mDir, "SLURM_ARRAY_TASK_ID=x1", "render --job shot.json --chunk 2").code, 2);
    EXPECT_EQ(runCliWith(mDir, "", "render --job shot.json --chunk 0 --task 0").code, 2);
    EXPECT_EQ(runCliWith(mDir, "", "render --job shot.json --task 0").code, 2) << "--task without --chunk";
    const CliRun single = runCliWith(mDir, "", "render in.1.vdb one.exr --chunk 1 --task 0");
    EXPECT_EQ(single.code, 2);
    EXPECT_NE(single.err.find("--chunk: a task's chunk of --frames: give --frames"), std::string::npos) << single.err;
    const CliRun same = runCliWith(mDir, "", "render --job shot.json in.#.vdb out/same.exr --chunk 1 --task 0");
    EXPECT_EQ(same.code, 2) << "one frame a task, but six tasks write out/same.exr";
    EXPECT_NE(same.err.find("out/same.exr has no frame pattern"), std::string::npos) << same.err;

    // The granted memory is the frame's budget: a frame over 3/4 of it stops (exit 5), an
    // explicit --max-memory wins.
    const CliRun over = runCliWith(mDir, "SLURM_ARRAY_TASK_ID=0 SLURM_MEM_PER_NODE=90", "render --job shot.json --chunk 1 --res 2048x2048");
    EXPECT_EQ(over.code, 5) << over.err;
    EXPECT_NE(over.err.find("over the memory budget of 67.5 MB (--max-memory)"), std::string::npos) << over.err;
    EXPECT_EQ(runCliWith(mDir, "SLURM_ARRAY_TASK_ID=0 SLURM_MEM_PER_NODE=90", "render --job shot.json --chunk 1 --res 2048x2048 --max-memory 1G").code, 0);
}

TEST_F(Farm, SubmitWritesTheArrayScriptRunsSbatchAndRecordsTheJob)
{
    // A stand-in sbatch: keeps its arguments and the script, answers as sbatch --parsable does.
    const std::string sbatch = mDir.file("sbatch");
    writeFile(sbatch, "#!/bin/sh\necho \"$@\" > " + mDir.file("sbatch_args") + "\ncp \"$2\" " + mDir.file("submitted.sh") + "\necho '4242;cluster'\n", true);
    const CliRun r = runCliWith(mDir, "", "submit shot.json --chunk 4 --cpus 2 --mem 4G --time 1:00:00 --partition render "
                                          "--max-running 5 --sbatch-option=--account=fx --sbatch " + sbatch);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string farm = mDir.file("shot.farm");
    EXPECT_NE(r.out.find("vdb_ewa: submitted job 4242: 2 tasks of 4 frames (frames 1-6); logs " + farm + "/logs/4242_*.log"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::is_directory(farm + "/logs"));
    const std::string script = slurp(mDir.file("submitted.sh"));
    EXPECT_EQ(slurp(farm + "/4242.sbatch"), script) << "the script kept under the job's id";
    for (const std::string& line : std::vector<std::string>{"#!/bin/sh\n", "#SBATCH --array=0-1%5\n", "#SBATCH --output=" + farm + "/logs/%A_%a.log\n",
             "#SBATCH --chdir=" + fs::path(mDir.file("x")).parent_path().string() + "\n", "#SBATCH --cpus-per-task=2\n", "#SBATCH --mem=4G\n",
             "#SBATCH --time=1:00:00\n", "#SBATCH --partition=render\n", "#SBATCH --account=fx\n", "#SBATCH --job-name=vdb_ewa:shot\n",
             " render --job " + mJob + " --frames 1-6 --chunk 4 --skip-newer-than ",
             "# Written by: vdb_ewa submit shot.json --chunk 4 --partition render --mem 4G --cpus 2 --time 1:00:00 --max-running 5 "
             "--sbatch-option=--account=fx --sbatch " + sbatch + "\n"}) {
        EXPECT_NE(script.find(line), std::string::npos) << line << "\n" << script;
    }
    std::smatch submitted;
    ASSERT_TRUE(std::regex_search(script, submitted, std::regex(R"( --skip-newer-than (\d+)\n)"))) << script;
    EXPECT_LE(std::abs(std::stoll(submitted[1].str()) - (long long)std::time(nullptr)), 60) << "the submission's time";
    EXPECT_EQ(slurp(mDir.file("sbatch_args")).substr(0, 11), "--parsable ");
    std::vector<std::string> warnings;
    const std::vector<Submission> recorded = readSubmissions(farm, warnings);
    ASSERT_EQ(recorded.size(), 1u);
    EXPECT_EQ(recorded[0].id, "4242");
    EXPECT_EQ(recorded[0].frames, parseFrameList("1-6"));
    EXPECT_EQ(recorded[0].chunk, 4);
    EXPECT_TRUE(warnings.empty());

    // The script runs as a task would: task 1 renders frames 5 and 6.
    const int status = std::system(("cd / && env SLURM_ARRAY_TASK_ID=1 sh " + mDir.file("submitted.sh") + " >" + mDir.file("task.log") + " 2>&1").c_str());
    EXPECT_EQ(status, 0) << slurp(mDir.file("task.log"));
    EXPECT_EQ(doneFrames(slurp(mDir.file("task.log"))), (std::vector<int>{5, 6})) << "in the job's folder\n" << slurp(mDir.file("task.log"));
    // Requeued (preemption, a node failure), the task does not redo the frames it wrote.
    std::system(("cd / && env SLURM_ARRAY_TASK_ID=1 sh " + mDir.file("submitted.sh") + " >" + mDir.file("task.log") + " 2>&1").c_str());
    EXPECT_TRUE(doneFrames(slurp(mDir.file("task.log"))).empty()) << slurp(mDir.file("task.log"));
    EXPECT_NE(slurp(mDir.file("task.log")).find("vdb_ewa: frame 6 skipped: out/o.6.exr was written after --skip-newer-than\n"), std::string::npos)
        << slurp(mDir.file("task.log"));
    // Older outputs are rendered again: the frames were written before that time.
    const CliRun rerender = runCliWith(mDir, "", "render --job shot.json --frames 5-6 --skip-newer-than " + std::to_string(std::time(nullptr) + 100));
    EXPECT_EQ(doneFrames(rerender.out), (std::vector<int>{5, 6})) << rerender.out;
    // status from another folder: the job's relative paths are the tasks' (the record's folder).
    const CliRun elsewhere = runCli(mDir, "status " + mJob + " --squeue ''", "", "cd / && ");
    EXPECT_NE(elsewhere.out.find(": 6 frames (1-6): 2 done, 0 running, 0 queued, 0 failed, 4 missing\n"), std::string::npos) << elsewhere.out;
    EXPECT_NE(elsewhere.out.find("missing: 1-4 (job 4242 task 0 never started)\n"), std::string::npos) << elsewhere.out;
    EXPECT_NE(elsewhere.out.find("to finish: vdb_ewa submit " + mJob + " --frames 1-4 --chunk 4 --partition render --mem 4G --cpus 2 --time 1:00:00 "
                                 "--max-running 5 --sbatch-option=--account=fx --sbatch " + sbatch + " --skip-existing\n"), std::string::npos) << elsewhere.out;

    // --skip-existing submits only the missing frames, chunked again; --dry-run prints the
    // script and writes nothing; --parsable prints the id alone.
    const CliRun dry = runCliWith(mDir, "", "submit shot.json --chunk 4 --skip-existing --dry-run --farm-dir other --sbatch " + sbatch);
    EXPECT_EQ(dry.code, 0) << dry.err;
    EXPECT_NE(dry.out.find("#SBATCH --array=0-0\n"), std::string::npos) << dry.out;
    EXPECT_NE(dry.out.find("#SBATCH --output=" + mDir.file("other") + "/logs/%A_%a.log\n"), std::string::npos) << dry.out;
    EXPECT_TRUE(std::regex_search(dry.out, std::regex(R"( --frames 1-4 --chunk 4 --skip-newer-than \d+ --skip-existing\n)"))) << dry.out;
    EXPECT_FALSE(fs::exists(mDir.file("other"))) << "a dry run writes nothing";
    EXPECT_EQ(fs::remove(mDir.file("submitted.sh")), true);
    const CliRun parsable = runCliWith(mDir, "", "submit shot.json --frames 1-2 --parsable --farm-dir other --sbatch " + sbatch);
    EXPECT_EQ(parsable.out, "4242\n");
    EXPECT_TRUE(fs::exists(mDir.file("other/4242.json")));
    const CliRun other = runCliWith(mDir, "", "status shot.json --farm-dir other --squeue ''");
    EXPECT_NE(other.out.find("missing: 1 (job 4242 task 0 never started)\nmissing: 2 (job 4242 task 1 never started)\n"), std::string::npos) << other.out;
    EXPECT_NE(other.out.find(" --farm-dir " + mDir.file("other") + " "), std::string::npos) << "absolute, for any folder\n" << other.out;
    for (int f = 1; f <= 4; ++f) writeFile(mDir.file("out/o." + std::to_string(f) + ".exr"), "x");
    const CliRun nothing = runCliWith(mDir, "", "submit shot.json --skip-existing --sbatch " + sbatch);
    EXPECT_EQ(nothing.code, 0);
    EXPECT_NE(nothing.out.find("every frame's output exists: nothing to submit"), std::string::npos) << nothing.out;
}

TEST_F(Farm, SubmitRefusesWhatEveryTaskWouldFailOnInOneLine)
{
    const std::string sbatch = mDir.file("sbatch");
    writeFile(sbatch, "#!/bin/sh\necho 'sbatch: error: Batch job submission failed: Invalid partition name specified' >&2\nexit 1\n", true);
    auto fails = [&](const std::string& args, int code, const std::string& needle) {
        const CliRun r = runCliWith(mDir, "", "submit " + args + " --sbatch " + sbatch);
        EXPECT_EQ(r.code, code) << args << "\n" << r.err;
        EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(fs::exists(mDir.file("shot.farm/4242.json")));
    };
    fails("shot.json --partition nope", 4, sbatch + ": the submission failed: error: Batch job submission failed: Invalid partition name specified");
    for (const auto& e : fs::directory_iterator(mDir.file("shot.farm"))) EXPECT_EQ(e.path().filename(), "logs") << "no script left behind";
    fails("shot.json --mem lots", 2, "--mem: 'lots' is not Slurm's memory size");
    fails("shot.json --time soon", 2, "--time: 'soon' is not Slurm's time");
    fails("shot.json --chunk 0", 2, "--chunk");
    fails("shot.json --frames 1-6 --res 10", 2, "unknown option");
    fails("nope.json", 3, "nope.json: cannot open the job file");
    writeFile(mJob, R"({"input": "in.#.vdb", "output": "out/o.#.exr", "res": "32x24"})");
    fails("shot.json", 2, "in.#.vdb: a frame pattern (#### or %04d) needs --frames");
    writeFile(mJob, R"({"input": "in.#.vdb", "output": "missing/o.#.exr", "frames": "1-6"})");
    fails("shot.json", 3, "folder");
    writeFile(mJob, R"({"input": "in.#.vdb", "output": "out/o.#.exr", "frames": "1-6", "fov": -4})");
    fails("shot.json", 2, "--fov");
    writeFile(mJob, R"({"input": "in.#.vdb", "output": "out/o.#.exr", "frames": "1-6"})");
    const CliRun none = runCliWith(mDir, "", "submit shot.json --sbatch " + mDir.file("no_sbatch"));
    EXPECT_EQ(none.code, 4);
    EXPECT_NE(none.err.find(mDir.file("no_sbatch") + ": the submission failed: not found (install Slurm's client"), std::string::npos) << none.err;
}

TEST_F(Farm, StatusListsDoneRunningQueuedFailedAndMissingFrames)
{
    // Two submissions: job 7 (tasks of 2: 1-2, 3-4, 5-6) and job 9 (frames 5-6, one task).
    const std::string farm = mDir.file("shot.farm");
    fs::create_directories(farm + "/logs");
    recordSubmission(farm, {"7", parseFrameList("1-6"), 2, "2026-11-26T17:00:00Z", mDir.file(""), ""});
    recordSubmission(farm, {"9", parseFrameList("5-6"), 2, "2026-11-26T17:10:00Z", mDir.file(""), " --chunk 2 --mem 1G"});
    writeFile(farm + "/garbage.json", "{");
    writeFile(mDir.file("out/o.1.exr"), "x");
    writeFile(farm + "/logs/7_0.log", "vdb_ewa: frame 1 done: out/o.1.exr (0.1 s, peak 9 MB)\nvdb_ewa: frame 2 done: out/o.2.exr (0.1 s, peak 9 MB)\n");
    writeFile(farm + "/logs/7_1.log", "vdb_ewa: frame 3 failed (exit 3): in.3.vdb: no such file\nvdb_ewa: frame 4 interrupted\n"
                                      "slurmstepd: error: *** JOB 8 ON node1 CANCELLED AT 2026-11-26T18:00:00 DUE TO PREEMPTION ***\n");
    writeFile(farm + "/logs/7_2.log", "vdb_ewa: frame 5 failed (exit 4): disk full\n");
    const std::string squeue = mDir.file("squeue");
    writeFile(squeue, "#!/bin/sh\necho '9_0 RUNNING'\necho '12_0 PENDING'\n", true);

    const CliRun r = runCliWith(mDir, "", "status shot.json --squeue " + squeue);
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.out.find("shot.json: 6 frames (1-6): 1 done, 2 running, 0 queued, 1 failed, 2 missing\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("running: 5-6\n"), std::string::npos) << "job 9 took over 5-6 from job 7\n" << r.out;
    EXPECT_NE(r.out.find("failed: frame 3: exit 3: in.3.vdb: no such file (job 7 task 1, " + farm + "/logs/7_1.log)\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("missing: 2 (job 7 task 0 wrote it, but the output is gone)\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("missing: 4 (job 7 task 1 cancelled due to preemption)\n"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("to finish"), std::string::npos) << "not while frames run\n" << r.out;
    EXPECT_NE(r.err.find("garbage.json: not a submission record: skipped"), std::string::npos) << r.err;

    // Job 9 ended; its task wrote frame 5 and died in frame 6. No queue: a warning.
    writeFile(squeue, "#!/bin/sh\necho 'squeue: error: Unable to contact slurm controller' >&2\nexit 1\n", true);
    writeFile(mDir.file("out/o.5.exr"), "x");
    writeFile(farm + "/logs/9_0.log", "vdb_ewa: frame 5 done: out/o.5.exr (0.1 s, peak 9 MB)\n");
    const CliRun later = runCliWith(mDir, "", "status shot.json --squeue " + squeue);
    EXPECT_EQ(later.code, 1);
    EXPECT_NE(later.out.find("2 done, 0 running, 0 queued, 1 failed, 3 missing\n"), std::string::npos) << later.out;
    EXPECT_NE(later.out.find("missing: 6 (job 9 task 0 ended before it)\n"), std::string::npos) << later.out;
    fs::remove(farm + "/logs/9_0.log");
    EXPECT_NE(runCliWith(mDir, "", "status shot.json --squeue ''").out.find("missing: 6 (job 9 task 0 never started)\n"), std::string::npos);
    EXPECT_NE(later.out.find("to finish: vdb_ewa submit shot.json --frames 2-4,6 --chunk 2 --mem 1G --skip-existing\n"), std::string::npos)
        << "the latest submission's options\n" << later.out;
    EXPECT_NE(later.err.find(squeue + ": error: Unable to contact slurm controller: the queue is unknown"), std::string::npos) << later.err;

    // Every frame done: exit 0. Without a farm folder the outputs alone say it.
    for (int f = 1; f <= 6; ++f) writeFile(mDir.file("out/o." + std::to_string(f) + ".exr"), "x");
    fs::remove_all(farm);
    const CliRun complete = runCliWith(mDir, "", "status shot.json --squeue ''");
    EXPECT_EQ(complete.code, 0) << complete.err;
    EXPECT_EQ(complete.out, "shot.json: 6 frames (1-6): 6 done, 0 running, 0 queued, 0 failed, 0 missing\n");
    const CliRun fresh = runCliWith(mDir, "", "status shot.json --frames 1-8 --squeue ''");
    EXPECT_NE(fresh.out.find("missing: 7-8 (never submitted)\n"), std::string::npos) << fresh.out;
}

TEST(FarmFolder, TaskLogsReadTheLastLineOfEachFrame)
{
    TempDir dir;
    writeFile(dir.file("t.log"), "0% done (peak 9 MB)\nvdb_ewa: frame 3 failed (exit 3): a: b\nvdb_ewa: frame 3 done: o.3.exr (1 s)\n"
                                 "vdb_ewa: frame -2 skipped: o.-2.exr exists\nvdb_ewa: frame 99999999999 done: x\n"
                                 "slurmstepd: error: *** JOB 12 ON n CANCELLED AT 2026-11-26T18:00:00 DUE TO TIME LIMIT ***\n");
    const TaskLog log = readTaskLog(dir.file("t.log"));
    ASSERT_EQ(log.frames.size(), 2u);
    EXPECT_EQ(log.frames.at(3).state, FrameEntry::Done) << "the last line wins";
    EXPECT_EQ(log.frames.at(-2).state, FrameEntry::Skipped);
    EXPECT_EQ(log.ended, "cancelled due to time limit");
    EXPECT_TRUE(readTaskLog(dir.file("none.log")).frames.empty());
    EXPECT_EQ(farmFolder("/a/b/shot.json", ""), "/a/b/shot.farm");
    EXPECT_EQ(farmFolder("/a/b/shot.json", "/c/../d"), "/d");
    // Submissions sort by time, then by id as a number: a cluster rebuilt restarts its ids.
    recordSubmission(dir.file(""), {"10", {1}, 1, "2026-11-26T17:00:00Z", "", ""});
    recordSubmission(dir.file(""), {"9", {1}, 1, "2026-11-26T17:00:00Z", "", ""});
    recordSubmission(dir.file(""), {"2", {1}, 1, "2026-11-26T18:00:00Z", "", ""});
    std::vector<std::string> warnings;
    std::vector<std::string> ids;
    for (const Submission& s : readSubmissions(dir.file(""), warnings)) ids.push_back(s.id);
    EXPECT_EQ(ids, (std::vector<std::string>{"9", "10", "2"}));
}

TEST(SbatchScript, DirectivesHoldPathsWithSpacesAndPercentsAndRefuseWhatTheyCannot)
{
    SbatchRequest r;
    r.program = "/opt/vdb ewa/bin/vdb_ewa";
    r.jobFile = "/shows/it's/shot.json";
    r.frames = parseFrameList("1-10");
    r.chunk = 3;
    r.submitted = 1800000000;
    r.workingFolder = "/shows/a b";
    r.logFolder = "/shows/a b/shot 100%.farm/logs";
    r.name = "vdb_ewa:sh 010";
    const std::string script = sbatchScript(r);
    for (const char* line : {"#SBATCH --array=0-3\n", "#SBATCH --output=\"/shows/a b/shot 100%%.farm/logs/%A_%a.log\"\n",
             "#SBATCH --chdir=\"/shows/a b\"\n", "#SBATCH --job-name=vdb_ewa:sh_010\n", "cd '/shows/a b' || exit 3",
             "exec '/opt/vdb ewa/bin/vdb_ewa' render --job '/shows/it'\\''s/shot.json' --frames 1-10 --chunk 3 --skip-newer-than 1800000000\n"}) {
        EXPECT_NE(script.find(line), std::string::npos) << line << "\n" << script;
    }
    // What an #SBATCH line cannot hold is refused in one line.
    const auto refused = [&](SbatchRequest bad, const std::string& needle) {
        try {
            sbatchScript(bad);
            ADD_FAILURE() << "accepted: " << needle;
        } catch (const ValueError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find(needle), std::string::npos) << message;
            EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        }
    };
    SbatchRequest bad = r;
    bad.workingFolder = "/shows/a\"b";
    refused(bad, "--chdir '/shows/a\"b' holds a quote, backslash or line break");
    bad = r;
    bad.logFolder = "/shows/x\ny";
    refused(bad, "'/shows/x\\ny/%A_%a.log'");
    bad = r;
    bad.extra = {"--comment=a b"};
    refused(bad, "--sbatch-option: '--comment=a b' is not one sbatch option");
    bad.extra = {"account=fx"};
    refused(bad, "is not one sbatch option");
}
