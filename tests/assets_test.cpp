/// @file assets_test.cpp
/// @brief The shared real-world assets (../shared/grids, $VDB_EWA_ASSETS): each fog volume
///        renders finite, framed as vdb_render frames it. Skipped when the assets are absent.
#include "fixtures.h"

#include <gtest/gtest.h>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

struct Asset
{
    std::string file;
    std::string camera; // from the assets' README, vdb_render syntax
};

void PrintTo(const Asset& a, std::ostream* os) { *os << a.file; }

class AssetTest : public ::testing::TestWithParam<Asset>
{
};

} // namespace

TEST_P(AssetTest, RendersFiniteAndFramedLikeVdbRender)
{
    const std::string dir = assetsDir();
    if (dir.empty()) GTEST_SKIP() << "shared assets not found (set VDB_EWA_ASSETS)";
    const std::string in = dir + "/" + GetParam().file;
    TempDir tmp;
    const std::string ours = tmp.file("ours.exr");
    const std::string args = " -res 240x135 " + GetParam().camera;
    ASSERT_EQ(std::system((std::string(VDB_EWA_CLI_PATH) + " render " + in + " " + ours + args).c_str()), 0);
    const Image b = readExr(ours);
    EXPECT_TRUE(b.allFinite());
    EXPECT_GT(alphaSum(b), 1.0);

    std::string ref = in;
    if (GetParam().file == "smoke_double.vdb") {
        // vdb_render reads float grids only: compare with a float copy of the same values.
        ref = tmp.file("float.vdb");
        writeGrid(openvdb::ConstPtrCast<openvdb::FloatGrid>(GridSource::open(in).impl().grid), ref);
    }
    const std::string vdbRender = vdbRenderPath();
    if (vdbRender.empty()) GTEST_SKIP() << "vdb_render is not installed";
    const std::string theirs = tmp.file("theirs.exr");
    ASSERT_EQ(std::system((vdbRender + " " + ref + " " + theirs + args + " -cpus 2").c_str()), 0);
    const Image a = readExr(theirs);
    std::size_t mask = 0;
    for (std::size_t i = 3; i < a.rgba.size(); i += 4) mask += a.rgba[i] > 0.2f;
    if (mask < 100) GTEST_SKIP() << "vdb_render's image is almost empty (" << mask << " pixels above alpha 0.2)";
    const double iou = alphaMaskIoU(a, b, 0.2f);
    std::printf("%s: alpha-mask IoU against vdb_render %.4f\n", GetParam().file.c_str(), iou);
    EXPECT_GT(iou, 0.85);
}

INSTANTIATE_TEST_SUITE_P(Shared, AssetTest,
    ::testing::Values(Asset{"smoke.vdb", "-translate -7.381,40.48,237.4 -lookat -7.381,40.48,0.4762"},
        Asset{"pyro.vdb", "-translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225"},
        Asset{"pig.vdb", "-translate 0,0,2.49 -lookat 0,0,0"},
        Asset{"fog_tommy_v5.vdb", "-translate 0,0.875,3.65 -lookat 0,0.875,0"},
        Asset{"smoke_double.vdb", "-translate 63.5,31.5,318 -lookat 63.5,31.5,31.5"},
        Asset{"brain_mri.vdb", "-translate 62.5,70.5,281 -lookat 62.5,70.5,41.5"}),
    [](const ::testing::TestParamInfo<Asset>& info) {
        std::string n = info.param.file.substr(0, info.param.file.find('.'));
        n.erase(std::remove(n.begin(), n.end(), '_'), n.end());
        return n;
    });
