/// @file cli_test.cpp
/// @brief `vdb_ewa` as a user runs it: every error path gives one line on stderr naming the
///        file and the problem, a documented non-zero exit, and no output file.
#include "cli_fixtures.h"
#include "fixtures.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <random>
#include <sstream>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

class Cli : public ::testing::Test
{
protected:
    void SetUp() override
    {
        mGrid = mDir.file("cloud.vdb");
        writeSampleGrid(SampleGrid::Cloud, mGrid, 0.08);
    }

    /// Expect a failure with @a code, one stderr line containing @a needle, and no output.
    void expectFailure(const std::string& args, int code, const std::string& needle)
    {
        const std::string out = mDir.file("out.exr");
        const CliRun r = runCli(mDir, args);
        EXPECT_EQ(r.code, code) << args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr: " << r.err;
        EXPECT_FALSE(std::filesystem::exists(out)) << args;
    }

    TempDir mDir;
    std::string mGrid;
};

} // namespace

TEST_F(Cli, RendersAnExr)
{
    const std::string out = mDir.file("out.exr");
    const CliRun r = runCli(mDir, "render " + mGrid + " " + out + " --res 64x48 -translate 0,0,5 -v");
    ASSERT_EQ(r.code, 0) << r.err;
    const Image img = readExr(out);
    EXPECT_EQ(img.width, 64);
    EXPECT_EQ(img.height, 48);
    EXPECT_GT(alphaSum(img), 20.0);
    EXPECT_NE(r.out.find("timings (s): load"), std::string::npos);
    // -v ends its timings with the process's peak memory: a process that loaded OpenVDB, OCIO
    // and a grid holds more than 5 MB, and this one far less than 5 GB.
    const std::size_t at = r.out.find("peak memory ");
    ASSERT_NE(at, std::string::npos) << r.out;
    const double mb = std::stod(r.out.substr(at + 12));
    EXPECT_GT(mb, 5.0);
    EXPECT_LT(mb, 5000.0);
}

TEST_F(Cli, OutputIsByteIdenticalForOneAndTwoThreads)
{
    const std::string one = mDir.file("one.exr"), two = mDir.file("two.exr");
    const std::string args = " --res 96x64 -translate 1,0.5,4 --kernel-sigma 0.8";
    ASSERT_EQ(runCli(mDir, "render " + mGrid + " " + one + args + " --threads 1").code, 0);
    ASSERT_EQ(runCli(mDir, "render " + mGrid + " " + two + args + " --threads 2").code, 0);
    const std::string a = slurp(one), b = slurp(two);
    EXPECT_GT(a.size(), 1000u);
    EXPECT_TRUE(a == b);
}

TEST_F(Cli, InputErrors)
{
    const std::string out = mDir.file("out.exr");
    expectFailure("render " + mDir.file("missing.vdb") + " " + out, 3, mDir.file("missing.vdb") + ": no such file");
    const std::string text = mDir.file("text.vdb");
    std::ofstream(text) << "not a vdb";
    expectFailure("render " + text + " " + out, 3, text + ": cannot read VDB file");
    const std::string bytes = slurp(mGrid);
    const std::string truncated = mDir.file("truncated.vdb");
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
    expectFailure("render " + truncated + " " + out, 3, truncated + ": ");
    expectFailure("render " + mGrid + " " + out + " --name smoke", 3, "no grid named 'smoke'");
    const std::string ints = mDir.file("int.vdb");
    auto i = openvdb::Int32Grid::create(0);
    i->setName("labels");
    writeGrid(i, ints);
    expectFailure("render " + ints + " " + out + " --name labels", 3, "holds int32 values");
}

TEST_F(Cli, ColorGridTintsAFogVolume)
{
    // A box of fog with a red colour grid in the same file: the scattered light is red only.
    const std::string file = mDir.file("tinted.vdb"), out = mDir.file("out.exr");
    auto density = makeBoxGrid(openvdb::Coord(-8), openvdb::Coord(7), 1.0f, 0.1);
    auto color = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    color->setTransform(density->transform().copy());
    color->setName("Cd");
    // Red over the density's trilinear support (one voxel beyond its active values), so that
    // the reference's trilinear colour lookups are red wherever there is density.
    color->tree().fill(openvdb::CoordBBox(openvdb::Coord(-9), openvdb::Coord(8)), openvdb::Vec3s(1.0f, 0.0f, 0.0f), true);
    openvdb::io::File(file).write({density, color});
    const CliRun r = runCli(mDir, "render " + file + " " + out + " --res 32x32 -translate 0,0,4 --color Cd --emission 0 -v");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("--shadow-res 1 --color Cd\n"), std::string::npos) << r.out;
    const Image img = readExr(out);
    const float* p = img.pixel(16, 16);
    EXPECT_EQ(p[1], 0.0f);
    EXPECT_EQ(p[2], 0.0f);
    // Red x white light: the red channel is the untinted render's, in the splatter and in the
    // reference alike (a red tint that also darkened or lightened red would show here).
    for (const std::string method : {"splat", "raymarch"}) {
        const std::string tinted = mDir.file("tinted.exr"), white = mDir.file("white.exr");
        const std::string common = " --res 32x32 -translate 0,0,4 --emission 0 --exr-type float --method " + method;
        ASSERT_EQ(runCli(mDir, "render " + file + " " + tinted + common + " --color Cd").code, 0);
        ASSERT_EQ(runCli(mDir, "render " + file + " " + white + common).code, 0);
        const Image a = readExr(tinted), b = readExr(white);
        EXPECT_GT(b.pixel(16, 16)[0], 0.01f) << method;
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x) {
                ASSERT_NEAR(a.pixel(x, y)[0], b.pixel(x, y)[0], 1e-5f + 1e-4f * b.pixel(x, y)[0]) << method << " " << x << "," << y;
                ASSERT_EQ(a.pixel(x, y)[1], 0.0f) << method;
                ASSERT_EQ(a.pixel(x, y)[3], b.pixel(x, y)[3]) << method << ": the tint changes no opacity";
            }
    }
    std::filesystem::remove(out);
    expectFailure("render " + file + " " + out + " --color density", 3, "density");
}

TEST_F(Cli, VerbosePrintsThePresetResolvedWithOverrides)
{
    const std::string out = mDir.file("out.exr");
    const CliRun draft = runCli(mDir, "render " + mGrid + " " + out + " --res 32x32 -translate 0,0,5 --quality draft -v");
    ASSERT_EQ(draft.code, 0) << draft.err;
    for (const char* value : {"--cutoff-radius 2 ", "--slab 4 ", "--shadow-res 2", "--tile-spacing 8 ", "--lod 10 ", "--lod-error 0.25 ", "--taper on ", "--prefilter on "}) {
        EXPECT_NE(draft.out.find(value), std::string::npos) << value << " in\n" << draft.out;
    }
    const CliRun over = runCli(mDir, "render " + mGrid + " " + out + " --res 32x32 -translate 0,0,5 --quality draft --lod 0 --prefilter off -v");
    ASSERT_EQ(over.code, 0) << over.err;
    EXPECT_NE(over.out.find("--lod 0 "), std::string::npos) << over.out;
    EXPECT_NE(over.out.find("--prefilter off "), std::string::npos) << over.out;
    EXPECT_NE(over.out.find("--slab 4 "), std::string::npos) << over.out;
}

TEST_F(Cli, ArgumentAndOutputErrors)
{
    const std::string out = mDir.file("out.exr");
    expectFailure("render " + mGrid + " " + out + " --res 0x10", 2, "--res");
    expectFailure("render " + mGrid + " " + out + " --prefilter maybe", 2, "--prefilter");
    expectFailure("render " + mGrid + " " + out + " --refine 5", 2, "--refine");
    expectFailure("render " + mGrid + " " + out + " --max-memory 12Q", 2, "--max-memory: '12Q' is not a size in bytes");
    expectFailure("render " + mGrid + " " + out + " --max-memory 10M", 2, "--max-memory must be");
    // Over the budget: exit 5, one line naming the file, the grid, the count and the budget.
    expectFailure("render " + mGrid + " " + out + " --res 2048x2048 -translate 0,0,5 --max-memory 64M", 5,
        mGrid + ": grid 'density': 4194304 pixels need 384 MB, over the memory budget of 64 MB (--max-memory)");
    expectFailure("render " + mGrid + " " + out + " --translate 1,2", 2, "--translate");
    expectFailure("render " + mGrid + " " + out + " --lookat 0,0,0 --rotate 0,0,0", 2, "not both");
    expectFailure("render " + mGrid + " " + out + " --fov 30 --focal 50", 2, "not both");
    expectFailure("render " + mGrid + " " + out + " --translate 0,0,0 --lookat 0,0,0", 2, "impossible camera");
    expectFailure("render " + mGrid + " " + out + " --near 0", 2, "--near");
    expectFailure("render " + mGrid + " " + out + " --slab -1", 2, "--slab");
    expectFailure("render " + mGrid + " " + out + " --aa bilinear", 2, "--aa");
    expectFailure("render " + mGrid + " " + out + " --lod -1", 2, "--lod");
    expectFailure("render " + mGrid + " " + out + " --lod-error 1.5", 2, "--lod-error");
    expectFailure("render " + mGrid + " " + out + " --taper maybe", 2, "--taper");
    expectFailure("render " + mGrid + " " + out + " --quality fast", 2, "--quality");
    expectFailure("render " + mGrid + " " + out + " --shader phong", 2, "--shader");
    expectFailure("render " + mGrid + " " + out + " --samples 0", 2, "--samples");
    expectFailure("render " + mGrid + " " + out + " --color Cd", 3, "Cd");
    expectFailure("render " + mGrid + " " + out + " --iso 0.1 --iso-opacity 2", 2, "--iso-opacity");
    expectFailure("render " + mGrid + " " + out + " --bogus 3", 2, "bogus");
    // Coefficients past 1e6 made Inf pixels; a shadow step of 1e-9 a light map past any memory.
    expectFailure("render " + mGrid + " " + out + " --emission 1e308", 2, "--emission must be in [0, 1e6]");
    expectFailure("render " + mGrid + " " + out + " --scatter 1e7", 2, "--scatter must be in [0, 1e6]");
    expectFailure("render " + mGrid + " " + out + " --light 0,1,0,3e38,1,1", 2, "--light colour must be in [0, 1e6]");
    expectFailure("render " + mGrid + " " + out + " --shadowstep 1e-9", 2, "--shadowstep must be finite and >= 0.001");
    expectFailure("render " + mGrid + " " + mDir.file("out.png"), 2, "unsupported output format");
    expectFailure("render " + mGrid + " " + mDir.file("no/such/dir/out.exr"), 3, "does not exist");
    // Every error is one line of at most 300 characters, whatever it quotes.
    const CliRun longName = runCli(mDir, "render " + mGrid + " " + out + " --name " + std::string(5000, 'n'));
    EXPECT_EQ(longName.code, 3) << longName.err;
    EXPECT_EQ(std::count(longName.err.begin(), longName.err.end(), '\n'), 1) << longName.err;
    EXPECT_LE(longName.err.size(), 301u) << longName.err;
    EXPECT_NE(longName.err.find("..."), std::string::npos) << longName.err;
    // A FIFO with no writer once blocked the open where no signal could stop it.
    const std::string fifo = mDir.file("pipe.vdb");
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    expectFailure("render " + fifo + " " + out, 3, "pipe.vdb: not a regular file");
}

TEST_F(Cli, EmptyAndOneVoxelGridsRenderWithTheDefaultCamera)
{
    // Centred at the origin, where the default eye is: once "impossible camera"; now the
    // camera looks down -z, says so, and the empty grid renders black with a warning.
    auto empty = openvdb::FloatGrid::create(0.0f);
    empty->setName("density");
    writeGrid(empty, mDir.file("empty.vdb"));
    auto one = makeBoxGrid(openvdb::Coord(0), openvdb::Coord(0), 1.0f, 0.1);
    one->setName("density");
    writeGrid(one, mDir.file("one.vdb"));
    for (const char* name : {"empty", "one"}) {
        const CliRun r = runCli(mDir, "render " + mDir.file(std::string(name) + ".vdb") + " " + mDir.file("o.exr") + " --res 32x18");
        EXPECT_EQ(r.code, 0) << name << ": " << r.err;
        EXPECT_NE(r.err.find("looking down -z"), std::string::npos) << name << ": " << r.err;
    }
}

TEST_F(Cli, FailureLeavesAnExistingOutputUntouched)
{
    const std::string out = mDir.file("keep.exr");
    ASSERT_EQ(runCli(mDir, "render " + mGrid + " " + out + " --res 32x32 -translate 0,0,5").code, 0);
    const std::string before = slurp(out);
    EXPECT_EQ(runCli(mDir, "render " + mGrid + " " + out + " --name missing").code, 3);
    EXPECT_EQ(runCli(mDir, "render " + mDir.file("nope.vdb") + " " + out).code, 3);
    EXPECT_EQ(slurp(out), before);
    // No temporary files are left behind.
    int files = 0;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(out).parent_path())) {
        files += e.path().filename().string().find(".tmp") != std::string::npos;
    }
    EXPECT_EQ(files, 0);
}

TEST_F(Cli, HelpDocumentsEveryOptionWithItsDefault)
{
    const CliRun r = runCli(mDir, "render --help");
    EXPECT_EQ(r.code, 0);
    for (const char* opt : {"--res", "--translate", "--rotate", "--lookat", "--up", "--camera", "--fov", "--focal",
             "--aperture", "--frame", "--near", "--far", "--name", "--absorb", "--scatter", "--light", "--gain",
             "--cutoff", "--shadowstep", "--step", "--kernel-sigma", "--lowpass", "--aa", "--cutoff-radius", "--slab",
             "--quality", "--exp", "--renormalize", "--taper", "--prefilter", "--precision", "--tile-spacing", "--refine", "--shadow-res", "--method",
             "--lod", "--lod-error", "--threads", "--max-memory", "--verbose", "--emission", "--ocio-config", "--working-space", "--output-space",
             "--preview", "--display", "--view", "--exr-type", "--compression", "--aov", "--deep", "--isovalue",
             "--shader", "--samples", "--color", "--iso", "--iso-opacity"}) {
        EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
    }
    EXPECT_NE(r.out.find("default: 1920x1080"), std::string::npos);
    EXPECT_NE(r.out.find("default: 0.1,0.1,0.1"), std::string::npos);
}

TEST_F(Cli, OutputOptionErrorsLeaveAnExistingOutputByteIdentical)
{
    const std::string out = mDir.file("out.exr");
    const std::string args = "render " + mGrid + " " + out + " --res 32x32 -translate 0,0,5 ";
    expectFailure(args + "--exr-type double", 2, "--exr-type");
    expectFailure(args + "--compression lzw", 2, "--compression");
    expectFailure(args + "--deep --compression piz", 2, "not valid for --deep");
    expectFailure(args + "--deep --compression zip", 2, "not valid for --deep");
    expectFailure(args + "--deep --aov shadow", 2, "--deep");
    expectFailure(args + "--aov depth", 2, "--aov");
    expectFailure(args + "--output-space 'Linear P3'", 2, "'Linear P3' is not in vdb_ewa's shipped config");
    expectFailure(args + "--working-space Raw", 2, "data space");
    expectFailure(args + "--preview " + mDir.file("p.jpg"), 2, "--preview writes a .png");
    expectFailure(args + "--view Filmic", 2, "--preview");
    expectFailure(args + "--preview " + mDir.file("p.png") + " --view Filmic", 2, "view 'Filmic'");
    expectFailure(args + "--preview " + mDir.file("no/p.png"), 3, "does not exist");
    expectFailure(args + "--emission 1 --absorb 0 --scatter 0", 2, "--emission");

    ASSERT_EQ(runCli(mDir, args).code, 0);
    const std::string before = slurp(out);
    for (const char* bad : {"--output-space Bogus", "--deep --compression dwaa", "--preview /no/such/p.png"}) {
        EXPECT_NE(runCli(mDir, args + bad).code, 0) << bad;
        EXPECT_EQ(slurp(out), before) << bad;
    }
    EXPECT_FALSE(std::filesystem::exists(mDir.file("p.png")));
}

TEST_F(Cli, OcioConfigPrecedenceAndFallback)
{
    const std::string out = mDir.file("out.exr");
    const std::string args = "render " + mGrid + " " + out + " --res 32x32 -translate 0,0,5 -v ";
    const CliRun shipped = runCli(mDir, args);
    ASSERT_EQ(shipped.code, 0) << shipped.err;
    EXPECT_NE(shipped.out.find("--ocio-config \"vdb_ewa's shipped config\" --working-space ACEScg"), std::string::npos) << shipped.out;
    EXPECT_TRUE(shipped.err.empty()) << shipped.err;

    const std::string config = mDir.file("studio.ocio");
    std::filesystem::copy_file(std::string(VDB_EWA_SOURCE_DIR) + "/share/ocio/config.ocio", config);
    const CliRun env = runCli(mDir, args + "--working-space lin_rec709", config);
    ASSERT_EQ(env.code, 0) << env.err;
    EXPECT_NE(env.out.find("--ocio-config " + config + " --working-space \"Linear Rec.709 (sRGB)\""), std::string::npos) << env.out;

    for (const std::string& broken : {mDir.file("missing.ocio"), std::string("ocio://studio-config-latest")}) {
        const CliRun r = runCli(mDir, args, broken);
        ASSERT_EQ(r.code, 0) << r.err;
        EXPECT_NE(r.err.find("vdb_ewa: warning: $OCIO: " + broken), std::string::npos) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.out.find("vdb_ewa's shipped config"), std::string::npos) << r.out;
    }
    const CliRun flag = runCli(mDir, args + "--ocio-config " + mDir.file("missing.ocio"), config);
    ASSERT_EQ(flag.code, 0) << flag.err;
    EXPECT_NE(flag.out.find("--ocio-config " + config), std::string::npos) << "a broken --ocio-config falls back to $OCIO";
}

TEST_F(Cli, WritesPreviewAndDeepFiles)
{
    const std::string out = mDir.file("out.exr"), png = mDir.file("out.png"), deep = mDir.file("deep.exr");
    const std::string args = " --res 48x32 -translate 0,0,5 ";
    const CliRun r = runCli(mDir, "render " + mGrid + " " + out + args + "--preview " + png + " --aov shadow --output-space lin_rec709");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(slurp(png).substr(1, 3), "PNG");
    EXPECT_GT(alphaSum(readExr(out)), 10.0);
    const CliRun d = runCli(mDir, "render " + mGrid + " " + deep + args + "--deep --exr-type float");
    ASSERT_EQ(d.code, 0) << d.err;
    ASSERT_EQ(runCli(mDir, "render " + mGrid + " " + out + args + "--exr-type float").code, 0);
    // OpenEXR's InputFile flattens deep files itself (CompositeDeepScanLine): an independent flatten.
    const Image flat = readExr(out), flattened = readExr(deep);
    ASSERT_EQ(flat.rgba.size(), flattened.rgba.size());
    for (std::size_t i = 0; i < flat.rgba.size(); ++i) EXPECT_NEAR(flattened.rgba[i], flat.rgba[i], 1e-3) << i;
}

TEST_F(Cli, OutputsThatAreAnInputAreRefused)
{
    // The input under another name: through ./ and .., a symlink to it or to its folder, a hard
    // link, a --preview path, the job file. Compared by device and inode, never by name; the
    // input stays byte-identical and nothing is written.
    namespace fs = std::filesystem;
    const std::string exrGrid = mDir.file("grid.exr"), pngGrid = mDir.file("grid.png");
    fs::copy_file(mGrid, exrGrid);
    fs::copy_file(mGrid, pngGrid);
    fs::create_directory(mDir.file("sub"));
    fs::create_directory_symlink(mDir.file("."), mDir.file("sub/up"));
    fs::create_symlink(exrGrid, mDir.file("link.exr"));
    fs::create_hard_link(mGrid, mDir.file("hard.exr"));
    const auto bytes = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string original = bytes(mGrid);
    const std::string cam = " --res 16x16 -translate 0,0,5";
    const struct
    {
        std::string input, args;
    } cases[] = {
        {exrGrid, mDir.file("sub/../grid.exr")},
        {exrGrid, mDir.file("sub/up/grid.exr")},
        {exrGrid, mDir.file("link.exr")},
        {mGrid, mDir.file("hard.exr")},
        {pngGrid, mDir.file("o.exr") + " --preview " + mDir.file("sub/up/grid.png")},
    };
    for (const auto& c : cases) {
        const CliRun r = runCli(mDir, "render " + c.input + " " + c.args + cam);
        EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find("is the same file as the input " + c.input), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(mDir.file("o.exr"))) << c.args;
    }
    EXPECT_EQ(bytes(mGrid), original);
    EXPECT_EQ(bytes(exrGrid), original);
    EXPECT_EQ(bytes(pngGrid), original);
    EXPECT_TRUE(fs::is_symlink(mDir.file("link.exr")));
    // A job file named as the output.
    const std::string job = mDir.file("job.exr");
    std::ofstream(job) << "{\"input\": \"" << mGrid << "\", \"res\": \"16x16\", \"translate\": \"0,0,5\"}\n";
    const std::string jobText = bytes(job);
    const CliRun r = runCli(mDir, "render --job " + job + " " + mGrid + " " + job);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_NE(r.err.find("is the same file as the input"), std::string::npos) << r.err;
    EXPECT_EQ(bytes(job), jobText);
}

// Random damage in a real file (1-8 bytes of the sample cloud replaced, 40 mutants, a fixed
// seed; every other mutant only in the last fifth, the leaf values, so that some still
// render): each run ends within 30 s with an image (exit 0, finite pixels) or one short error
// line and no output (exit 3), never a crash, a hang or a runaway; the input stays as it was.
TEST_F(Cli, RandomlyDamagedFilesRenderOrFailCleanly)
{
    std::ifstream in(mGrid, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string mutant = mDir.file("mutant.vdb"), out = mDir.file("out.exr");
    std::mt19937 rng(15);
    int rendered = 0, refused = 0;
    for (int m = 0; m < 40; ++m) {
        std::string damaged = bytes;
        const int changes = 1 + int(rng() % 8);
        const std::size_t from = m % 2 ? damaged.size() * 4 / 5 : 0;
        for (int c = 0; c < changes; ++c) damaged[from + rng() % (damaged.size() - from)] = char(rng() % 256);
        std::ofstream(mutant, std::ios::binary | std::ios::trunc) << damaged;
        std::filesystem::remove(out);
        const auto t0 = std::chrono::steady_clock::now();
        const CliRun r = runCli(mDir, "render " + mutant + " " + out + " --res 64x48 -translate 0,0,5 --max-memory 512M -q");
        EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 30.0) << m;
        ASSERT_TRUE(r.code == 0 || r.code == 3) << "mutant " << m << ": exit " << r.code << "\n" << r.err;
        EXPECT_EQ(slurp(mutant), damaged) << "the input was changed";
        if (r.code == 0) {
            ++rendered;
            const Image img = readExr(out);
            EXPECT_TRUE(std::all_of(img.rgba.begin(), img.rgba.end(), [](float v) { return std::isfinite(v); })) << m;
        } else {
            ++refused;
            EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
            EXPECT_LE(r.err.size(), 301u) << r.err;
            EXPECT_NE(r.err.find(mutant), std::string::npos) << r.err;
            EXPECT_FALSE(std::filesystem::exists(out)) << m;
        }
    }
    std::printf("40 mutants: %d rendered, %d refused\n", rendered, refused);
    EXPECT_GT(rendered, 0);
    EXPECT_GT(refused, 0);
}
