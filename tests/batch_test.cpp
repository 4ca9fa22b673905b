/// @file batch_test.cpp
/// @brief Batch jobs as a render farm runs them: frame lists and patterns, sequences with a
///        missing frame, resuming a killed job, job files, progress lines, exit codes and a
///        clean stop on SIGTERM / SIGINT.
#include "cli_fixtures.h"

#include "../cmd/vdb_ewa/frame_sequence.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <regex>
#include <thread>

using namespace vdb_ewa;
using namespace vdb_ewa::test;
using vdb_ewa::cli::framePath;
using vdb_ewa::cli::hasFramePattern;
using vdb_ewa::cli::parseFrameList;

namespace fs = std::filesystem;

namespace {

/// Hidden temporary files a write leaves if it is killed (.NAME.tmpPID_N).
int temporaryFiles(const TempDir& dir)
{
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir.file(""))) n += e.path().filename().string().find(".tmp") != std::string::npos;
    return n;
}

/// Poll @a done every 20 ms for up to @a seconds.
template <typename F>
bool waitFor(F done, double seconds)
{
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (done()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return done();
}

/// The percentages of the `NN% done` lines in @a out.
std::vector<int> percents(const std::string& out)
{
    std::vector<int> p;
    static const std::regex line(R"((^|\n)(\d+)% done \((ETA \d+:\d\d, )?peak \d+ MB\)(?=\n))");
    for (auto it = std::sregex_iterator(out.begin(), out.end(), line); it != std::sregex_iterator(); ++it) {
        p.push_back(std::stoi((*it)[2]));
    }
    return p;
}

class Batch : public ::testing::Test
{
protected:
    void SetUp() override
    {
        for (int f : {1, 2, 4}) writeSampleGrid(SampleGrid::Cloud, mDir.file("smoke." + std::to_string(10000 + f).substr(1) + ".vdb"), 0.08);
    }
    TempDir mDir;
};

} // namespace

TEST(FrameList, ParsesRangesStepsAndLists)
{
    EXPECT_EQ(parseFrameList("1-5"), (std::vector<int>{1, 2, 3, 4, 5}));
    EXPECT_EQ(parseFrameList("1-10x3"), (std::vector<int>{1, 4, 7, 10}));
    EXPECT_EQ(parseFrameList("1-3,20"), (std::vector<int>{1, 2, 3, 20}));
    EXPECT_EQ(parseFrameList("7"), (std::vector<int>{7}));
    EXPECT_EQ(parseFrameList("5,1-3,2"), (std::vector<int>{5, 1, 2, 3})) << "order kept, repeats dropped";
    EXPECT_EQ(parseFrameList("-2-1"), (std::vector<int>{-2, -1, 0, 1}));
    EXPECT_EQ(parseFrameList("-5--3"), (std::vector<int>{-5, -4, -3}));
    for (const char* bad : {"", "1-", "a", "5-1", "1-10x0", "1-10x", "1,,2", "1-2-3", "1 - 2", "99999999999", "0-2000000000"}) {
        EXPECT_THROW(parseFrameList(bad), ValueError) << "'" << bad << "'";
    }
}

TEST(FrameList, ReplacesHashAndPrintfPatterns)
{
    EXPECT_TRUE(hasFramePattern("smoke.####.vdb"));
    EXPECT_TRUE(hasFramePattern("smoke.%04d.vdb"));
    EXPECT_TRUE(hasFramePattern("smoke.%d.vdb"));
    EXPECT_FALSE(hasFramePattern("smoke.vdb"));
    EXPECT_FALSE(hasFramePattern("smoke%.vdb"));
    EXPECT_EQ(framePath("smoke.####.vdb", 7), "smoke.0007.vdb");
    EXPECT_EQ(framePath("smoke.#.vdb", 1234), "smoke.1234.vdb");
    EXPECT_EQ(framePath("smoke.%04d.vdb", 12), "smoke.0012.vdb");
    EXPECT_EQ(framePath("smoke.%d.vdb", 12), "smoke.12.vdb");
    EXPECT_EQ(framePath("smoke.###.vdb", -4), "smoke.-004.vdb");
    EXPECT_EQ(framePath("dir/smoke.vdb", 3), "dir/smoke.vdb");
    EXPECT_THROW(framePath("s.####.%04d.vdb", 1), ValueError);
}

TEST_F(Batch, SequenceWithAMissingFrameRendersTheRestAndListsIt)
{
    const CliRun r = runCli(mDir, "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("out.####.exr") +
        " --frames 1-4 --res 48x32 -translate 0,0,5");
    EXPECT_EQ(r.code, 3) << "bad input: a frame is missing\n" << r.err;
    EXPECT_NE(r.err.find("frame 3 failed (exit 3): " + mDir.file("smoke.0003.vdb") + ": no such file"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("1 of 4 frames failed: 3\n"), std::string::npos) << r.err;
    for (int f : {1, 2, 4}) EXPECT_TRUE(fs::exists(mDir.file("out.000" + std::to_string(f) + ".exr"))) << f;
    EXPECT_FALSE(fs::exists(mDir.file("out.0003.exr")));
    // Each output comes from its own frame and says so.
    const Image one = readExr(mDir.file("out.0001.exr"));
    EXPECT_GT(alphaSum(one), 5.0);
    EXPECT_NE(slurp(mDir.file("out.0004.exr")).find("smoke.0004.vdb"), std::string::npos);
    // Progress lines for farm managers: rising multiples of 5 up to 100.
    const std::vector<int> p = percents(r.out);
    ASSERT_GE(p.size(), 3u) << r.out;
    EXPECT_EQ(p.front(), 0);
    EXPECT_EQ(p.back(), 100);
    for (std::size_t i = 1; i < p.size(); ++i) EXPECT_GT(p[i], p[i - 1]);
    // -q: nothing on stdout.
    EXPECT_EQ(runCli(mDir, "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("q.####.exr") +
        " --frames 1-2 --res 48x32 -translate 0,0,5 -q").out, "");
}

TEST_F(Batch, AFrameThatCannotBeWrittenIsARenderFailure)
{
    // The pattern is in the folder name: frame 1's folder exists, frame 2's does not.
    fs::create_directory(mDir.file("d0001"));
    const CliRun r = runCli(mDir, "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("d####/out.exr") +
        " --frames 1-2 --res 48x32 -translate 0,0,5");
    EXPECT_EQ(r.code, 4) << r.err;
    EXPECT_NE(r.err.find("frame 2 failed (exit 4): "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("1 of 2 frames failed: 2\n"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(mDir.file("d0001/out.exr")));
}

TEST_F(Batch, FramePatternErrors)
{
    const std::string in = mDir.file("smoke.####.vdb");
    auto fails = [&](const std::string& args, const std::string& needle) {
        const CliRun r = runCli(mDir, "render " + args);
        EXPECT_EQ(r.code, 2) << args;
        EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    };
    fails(in + " " + mDir.file("out.exr") + " --frames 1-2", "every frame would overwrite it");
    fails(in + " " + mDir.file("out.####.exr"), "needs --frames");
    fails(mDir.file("smoke.0001.vdb") + " " + mDir.file("out.####.exr") + " --frames 1-2", "has no frame pattern");
    fails(in + " " + mDir.file("out.####.exr") + " --frames 3-1", "ends before it starts");
    EXPECT_FALSE(fs::exists(mDir.file("out.0001.exr")));
}

TEST_F(Batch, SkipExistingResumesAKilledJobWithoutRedoingFinishedFrames)
{
    writeSampleGrid(SampleGrid::Cloud, mDir.file("smoke.0003.vdb"), 0.08);
    // A slow job (the raymarch reference), killed once its first frame is written.
    const std::vector<std::string> slow{"render", mDir.file("smoke.####.vdb"), mDir.file("out.####.exr"), "--frames", "1-4",
        "--res", "480x270", "--translate", "0,0,5", "--method", "raymarch", "--step", "0.25"};
    {
        BackgroundCli job(mDir, slow);
        ASSERT_TRUE(job.started());
        ASSERT_TRUE(waitFor([&] { return fs::exists(mDir.file("out.0001.exr")); }, 120.0)) << job.err();
        job.signal(SIGKILL);
        EXPECT_EQ(job.wait(), 128 + SIGKILL);
    }
    ASSERT_FALSE(fs::exists(mDir.file("out.0004.exr"))) << "the job finished before it was killed";
    const auto firstTime = fs::last_write_time(mDir.file("out.0001.exr"));
    const std::string firstBytes = slurp(mDir.file("out.0001.exr"));
    // Resume, fast: finished frames are skipped, not redone.
    const CliRun r = runCli(mDir, "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("out.####.exr") +
        " --frames 1-4 --res 480x270 -translate 0,0,5 --quality draft --skip-existing -v");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("vdb_ewa: frame 1 skipped: " + mDir.file("out.0001.exr") + " exists\n"), std::string::npos) << r.out;
    EXPECT_EQ(fs::last_write_time(mDir.file("out.0001.exr")), firstTime);
    EXPECT_EQ(slurp(mDir.file("out.0001.exr")), firstBytes);
    for (int f : {2, 3, 4}) EXPECT_GT(alphaSum(readExr(mDir.file("out.000" + std::to_string(f) + ".exr"))), 5.0) << f;
    // Each frame's line gives its time and the peak memory; the summary counts in English.
    EXPECT_TRUE(std::regex_search(r.out, std::regex(R"(vdb_ewa: frame 2 done: \S+out\.0002\.exr \(\d+\.\d\d s, peak \d+ MB\)\n)"))) << r.out;
    EXPECT_NE(r.out.find("vdb_ewa: 3 frames written, 1 skipped (--skip-existing)"), std::string::npos) << r.out;
    const CliRun one = runCli(mDir, "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("one.####.exr") +
        " --frames 2 --res 16x16 -translate 0,0,5 --quality draft");
    EXPECT_NE(one.out.find("vdb_ewa: 1 frame written, 0 skipped (--skip-existing)"), std::string::npos) << one.out;
}

TEST_F(Batch, SigtermAndSigintStopCleanlyWithoutOutput)
{
    for (const int sig : {SIGTERM, SIGINT}) {
        const std::string out = mDir.file("stopped.exr");
        fs::remove(out);
        BackgroundCli job(mDir, {"render", mDir.file("smoke.0001.vdb"), out, "--res", "640x360", "--translate", "0,0,5",
                                    "--method", "raymarch", "--step", "0.1"});
        ASSERT_TRUE(job.started());
        // Signal once the rays are being marched (progress past the kernels and shadows).
        ASSERT_TRUE(waitFor([&] { const auto p = percents(job.out()); return !p.empty() && p.back() >= 20; }, 120.0)) << job.out();
        const auto t0 = std::chrono::steady_clock::now();
        job.signal(sig);
        const int code = job.wait();
        const double latency = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        EXPECT_EQ(code, 130) << job.err();
        EXPECT_LT(latency, 1.0);
        EXPECT_NE(job.err().find("interrupted: 0 of 1 frame written"), std::string::npos) << job.err();
        EXPECT_FALSE(fs::exists(out));
        EXPECT_EQ(temporaryFiles(mDir), 0);
        EXPECT_LT(percents(job.out()).back(), 100);
    }
}

// A stop signal ends a frame within 0.5 s in every stage, with exit 130 and nothing written.
// The render's stages check the cancel every 50 ms at most; reading a grid (held here by
// VDB_EWA_TEST_STALL, as a hung network file would hold it) and writing the image (a 4096^2
// float EXR: seconds of zip compression) never check, and the CLI's watchdog ends them
// kStopGraceMs after the signal, removing the temporary output.
TEST_F(Batch, EveryStageStopsWithinHalfASecondOfASignal)
{
    const std::string dense = mDir.file("dense.vdb");
    writeSampleGrid(SampleGrid::Cloud, dense, 0.02);
    const std::string out = mDir.file("stage.exr");
    struct Stage
    {
        const char* name;
        int percent; ///< signal once a progress line reaches it (the stages' shares: renderer.cpp)
        std::vector<std::string> options;
    };
    // Release: kernels 0.2 s, shadows 0.3 s, projection 0.6 s, rasterisation 3.5 s; the write
    // of the 4096^2 frame with three AOVs 2 s (ASan: 2, 14, 3, 57 and 4 s). The signal goes
    // out within 20 ms of the stage's first progress line.
    const std::vector<std::string> slow{"--translate", "0,0,5", "--quality", "final"};
    const std::vector<std::string> write{"--translate", "0,0,30", "--quality", "draft", "--res", "4096x4096", "--exr-type",
        "float", "--compression", "zip", "--aov", "shadow,emission,transmittance"};
    const Stage stages[] = {{"read", -1, slow}, {"kernels", 0, slow}, {"shadows", 10, slow}, {"projection", 35, slow},
        {"rasterisation", 45, slow}, {"write", 100, write}};
    for (const Stage& stage : stages) {
        std::vector<std::string> args{"render", dense, out};
        args.insert(args.end(), stage.options.begin(), stage.options.end());
        if (stage.percent < 0) setenv("VDB_EWA_TEST_STALL", "read", 1);
        BackgroundCli job(mDir, args);
        unsetenv("VDB_EWA_TEST_STALL");
        ASSERT_TRUE(job.started());
        ASSERT_TRUE(waitFor([&] {
            if (stage.percent < 0) return job.err().find("stalling") != std::string::npos;
            const auto p = percents(job.out());
            return !p.empty() && p.back() >= stage.percent;
        }, 300.0)) << stage.name << "\n" << job.out() << job.err();
        const auto t0 = std::chrono::steady_clock::now();
        job.signal(SIGINT);
        const int code = job.wait();
        const double latency = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("SIGINT in %s: exit %d after %.3f s\n", stage.name, code, latency);
        EXPECT_EQ(code, 130) << stage.name << ": " << job.err();
        EXPECT_LT(latency, 0.5 * kLatencySlack) << stage.name;
        EXPECT_FALSE(fs::exists(out)) << stage.name;
        EXPECT_EQ(temporaryFiles(mDir), 0) << stage.name;
    }
}

// A farm's status reads which frame a stopped task was on from its log: a stopped sequence
// prints one `frame N interrupted` line for the frame in flight, whether the render's own
// check stops it, the watchdog ends a read that never checks, or the stop lands between two
// frames (then N is the frame that did not start: the CI's slurm test once saw no line).
TEST_F(Batch, AStoppedSequenceNamesTheFrameItWasOn)
{
    struct Case
    {
        const char* stall;   ///< VDB_EWA_TEST_STALL
        const char* waitFor; ///< signal once stderr or stdout holds this
        int interrupted;
        int written;
    };
    const Case cases[] = {{"read", "stalling", 1, 0}, {"between-frames", "frame 1 done", 2, 1}};
    for (const Case& c : cases) {
        setenv("VDB_EWA_TEST_STALL", c.stall, 1);
        BackgroundCli job(mDir, {"render", mDir.file("smoke.####.vdb"), mDir.file("seq.####.exr"), "--frames", "1,2,4",
                                    "--res", "32x18", "--translate", "0,0,5", "--quality", "draft"});
        unsetenv("VDB_EWA_TEST_STALL");
        ASSERT_TRUE(job.started());
        ASSERT_TRUE(waitFor([&] { return (job.err() + job.out()).find(c.waitFor) != std::string::npos; }, 120.0))
            << c.stall << "\n" << job.out() << job.err();
        job.signal(SIGTERM);
        EXPECT_EQ(job.wait(), 130) << c.stall << ": " << job.err();
        const std::string err = job.err();
        std::smatch m;
        std::vector<int> lines;
        for (auto it = err.cbegin(); std::regex_search(it, err.cend(), m, std::regex(R"(vdb_ewa: frame (\d+) interrupted\n)"));
             it = m.suffix().first) {
            lines.push_back(std::stoi(m[1]));
        }
        EXPECT_EQ(lines, std::vector<int>{c.interrupted}) << c.stall << ": " << err;
        EXPECT_NE(err.find("interrupted: " + std::to_string(c.written) + " of 3 frames written"), std::string::npos)
            << c.stall << ": " << err;
        EXPECT_EQ(temporaryFiles(mDir), 0) << c.stall;
    }
}

TEST_F(Batch, JobFileHoldsTheSettingsAndTheCommandLineOverridesIt)
{
    const std::string job = mDir.file("shot.json");
    std::ofstream(job) << R"({"input": ")" << mDir.file("smoke.####.vdb") << R"(", "output": ")" << mDir.file("job.####.exr")
                       << R"(", "frames": "1-2", "res": "64x48", "translate": [0, 0, 5], "quality": "draft",
                          "aov": ["shadow", "emission"], "exr-type": "float", "skip-existing": true})";
    const CliRun r = runCli(mDir, "render --job " + job + " --res 32x16 -v");
    ASSERT_EQ(r.code, 0) << r.err;
    const Image img = readExr(mDir.file("job.0002.exr"));
    EXPECT_EQ(img.width, 32) << "the command line's --res wins";
    EXPECT_EQ(img.height, 16);
    EXPECT_NE(r.out.find("--translate 0,0,5"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--slab 4"), std::string::npos) << "draft from the job";
    EXPECT_NE(r.out.find("--aov shadow,emission"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--exr-type float"), std::string::npos) << r.out;
    // Positionals on the command line win too; flags from the job apply (skip-existing).
    const CliRun again = runCli(mDir, "render --job " + job + " " + mDir.file("smoke.####.vdb") + " " +
        mDir.file("other.####.exr") + " -v");
    ASSERT_EQ(again.code, 0) << again.err;
    EXPECT_TRUE(fs::exists(mDir.file("other.0001.exr")));
    const CliRun skip = runCli(mDir, "render --job " + job + " -v");
    EXPECT_NE(skip.out.find(" exists\n"), std::string::npos) << skip.out;

    // Unknown keys and wrong values name the key; a broken file names the file.
    auto fails = [&](const std::string& json, int code, const std::string& needle) {
        std::ofstream(job) << json;
        const CliRun f = runCli(mDir, "render --job " + job);
        EXPECT_EQ(f.code, code) << json << "\n" << f.err;
        EXPECT_NE(f.err.find(needle), std::string::npos) << f.err;
        EXPECT_EQ(std::count(f.err.begin(), f.err.end(), '\n'), 1) << f.err;
    };
    fails(R"({"input": "a.vdb", "output": "b.exr", "resolution": "64x48"})", 2, job + ": unknown key 'resolution'");
    fails(R"({"input": "a.vdb", "output": "b.exr", "res": {"w": 1}})", 2, job + ": res: expected");
    fails(R"({"input": "a.vdb", "output": "b.exr", "skip-existing": "yes"})", 2, job + ": skip-existing: expected true or false");
    fails(R"({"output": "b.exr"})", 2, "give input and output");
    fails(R"({"input": )", 3, job + ": not a JSON job file");
    fails(R"([1, 2])", 2, job + ": a job file holds one JSON object");
    fails(R"({"input": "a.vdb", "output": "b.exr", "scatter": [1e999, 1, 1]})", 3, job + ": not a JSON job file (");
    // Nested a million levels deep, in a key and at the top: once a stack overflow (SIGSEGV).
    // Up to 64 levels are JSON's business; the option then refuses a value of that shape.
    const auto nested = [](int depth) { return std::string(std::size_t(depth), '[') + std::string(std::size_t(depth), ']'); };
    fails(R"({"input": "a.vdb", "output": "b.exr", "light": )" + nested(1000000) + "}", 3, job + ": not a JSON job file (nested deeper than 64 levels)");
    fails(nested(1000000), 3, job + ": not a JSON job file (nested deeper than 64 levels)");
    fails(R"({"input": "a.vdb", "output": "b.exr", "light": )" + nested(63) + "}", 2, job + ": light: expected a list of numbers");
    const CliRun directory = runCli(mDir, "render --job " + mDir.file(""));
    EXPECT_EQ(directory.code, 3) << directory.err;
    EXPECT_NE(directory.err.find("not a regular file, so not a job file"), std::string::npos) << directory.err;
    const CliRun missing = runCli(mDir, "render --job " + mDir.file("nope.json"));
    EXPECT_EQ(missing.code, 3);
    EXPECT_NE(missing.err.find("nope.json: cannot open the job file"), std::string::npos) << missing.err;
}

TEST_F(Batch, SkipExistingRendersAFrameWhosePreviewIsMissing)
{
    // A job killed between a frame's EXR and its preview left the EXR alone: the frame is not
    // done, and --skip-existing once skipped it, leaving the preview missing for good.
    const std::string args = "render " + mDir.file("smoke.####.vdb") + " " + mDir.file("p.####.exr") + " --frames 1-2 --res 64x36" +
                             " -translate 0,0,5 --quality draft --preview " + mDir.file("p.####.png") + " --skip-existing -v";
    ASSERT_EQ(runCli(mDir, args).code, 0);
    fs::remove(mDir.file("p.0001.png"));
    const CliRun r = runCli(mDir, args);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.out.find(mDir.file("p.0001.exr") + " exists"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(mDir.file("p.0002.exr") + " exists"), std::string::npos) << r.out;
    EXPECT_TRUE(fs::exists(mDir.file("p.0001.png")));
}
