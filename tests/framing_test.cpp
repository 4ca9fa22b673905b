/// @file framing_test.cpp
/// @brief The same arguments frame the same image as vdb_render: alpha masks of both on a
///        generated cloud. Skipped when vdb_render is not installed.
#include "fixtures.h"

#include <gtest/gtest.h>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

struct Framing
{
    std::string name;
    std::string args; // vdb_render and vdb_ewa spelling (single-dash long options)
};

void PrintTo(const Framing& f, std::ostream* os) { *os << f.args; }

class FramingTest : public ::testing::TestWithParam<Framing>
{
};

} // namespace

TEST_P(FramingTest, AlphaMaskMatchesVdbRender)
{
    const std::string vdbRender = vdbRenderPath();
    if (vdbRender.empty()) GTEST_SKIP() << "vdb_render is not installed";
    TempDir dir;
    const std::string grid = dir.file("cloud.vdb");
    writeSampleGrid(SampleGrid::Cloud, grid, 0.05);
    const std::string theirs = dir.file("theirs.exr"), ours = dir.file("ours.exr");
    const std::string args = " -res 192x108 " + GetParam().args;
    ASSERT_EQ(std::system((vdbRender + " " + grid + " " + theirs + args + " -cpus 2").c_str()), 0);
    ASSERT_EQ(std::system((std::string(VDB_EWA_CLI_PATH) + " render " + grid + " " + ours + args).c_str()), 0);
    const Image a = readExr(theirs), b = readExr(ours);
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    EXPECT_GT(alphaSum(a), 200.0) << "the cloud is not in view";
    // Framing decides where the silhouette is; our Gaussian kernels blur the faint fringe a
    // little more than vdb_render's trilinear samples, so the mask is taken at alpha 0.5 and 0.2.
    const double iou50 = alphaMaskIoU(a, b, 0.5f), iou20 = alphaMaskIoU(a, b, 0.2f);
    std::printf("framing %s: IoU %.4f (alpha > 0.5), %.4f (alpha > 0.2)\n", GetParam().name.c_str(), iou50, iou20);
    EXPECT_GT(iou50, 0.95);
    EXPECT_GT(iou20, 0.95);
}

INSTANTIATE_TEST_SUITE_P(Cameras, FramingTest,
    ::testing::Values(Framing{"DefaultTarget", "-translate 1,0.5,5"},
        Framing{"LookAtUp", "-translate 0,3,4 -lookat 0.2,0,0 -up 0.3,1,0 -fov 30"},
        Framing{"Rotate", "-translate 2,0.5,4 -rotate -5,25,10 -focal 35"},
        Framing{"Ortho", "-camera ortho -translate 0,0,5 -lookat 0,0,0 -frame 3"},
        Framing{"Inside", "-translate 0,0,0.9 -lookat 0,0,0 -fov 90"}),
    [](const ::testing::TestParamInfo<Framing>& info) { return info.param.name; });
