/// @file assets_test.cpp
/// @brief The shared real-world assets (../shared/grids, $VDB_EWA_ASSETS): each fog volume
///        renders finite, framed as vdb_render frames it. Skipped when the assets are absent.
#include "fixtures.h"
#include "image_read.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

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

TEST(AssetColour, VdbRenderColouredLineWithNoColourOptionWritesWhatVdbRenderWrites)
{
    // The drop-in promise for colour: vdb_render's coloured command line as it is, no colour
    // option, and the files hold what vdb_render's hold. The EXR: values in the input space
    // (linear Rec.709), tagged so, within 40 dB of vdb_render's converged image as both are
    // written (33 dB when the EXR held ACEScg). The 8-bit daily: the EXR's values through the
    // plain sRGB curve, not a tone map (the ACES SDR view was 32.8 codes off at the 99th
    // percentile on a cloud).
    const std::string dir = assetsDir();
    if (dir.empty()) GTEST_SKIP() << "shared assets not found (set VDB_EWA_ASSETS)";
    const std::string vdbRender = vdbRenderPath();
    if (vdbRender.empty()) GTEST_SKIP() << "vdb_render is not installed";
    const std::string in = dir + "/pyro.vdb";
    TempDir tmp;
    const std::string line = " -res 480x270 -translate 0.225,2.175,15.75 -lookat 0.225,2.175,-0.225 "
                             "-light 0.3,0.3,0,1,0.6,0.3 -scatter 0.6,0.5,0.4 -absorb 0.05,0.05,0.05";
    const std::string theirs = tmp.file("theirs.exr"), ours = tmp.file("ours.exr"), daily = tmp.file("ours.png");
    ASSERT_EQ(std::system((vdbRender + " " + in + " " + theirs + line + " -step 0.125 -shadowstep 0.375 -cpus 2").c_str()), 0);
    const std::string cli = std::string(VDB_EWA_CLI_PATH) + " " + in + " ";
    ASSERT_EQ(std::system((cli + ours + line + " --quality high -q").c_str()), 0);
    ASSERT_EQ(std::system((cli + daily + line + " --quality high -q").c_str()), 0);

    const Image reference = readExr(theirs), exr = readExr(ours);
    const double psnr = -20.0 * std::log10(rmse(exr, reference));
    std::printf("pyro, vdb_render's coloured line, --quality high, no colour option: %.1f dB against vdb_render's converged image\n", psnr);
    EXPECT_GE(psnr, 40.0);
    const ImageFile header = readImageFile(ours);
    EXPECT_EQ(header.spec.get_string_attribute("oiio:ColorSpace"), "Linear Rec.709 (sRGB)");
    EXPECT_EQ(header.spec.get_string_attribute("colorInteropID"), "lin_rec709_scene");

    // The PNG against the sRGB curve (IEC 61966-2-1) of the EXR's beauty over black, in codes.
    const ImageFile png = readImageFile(daily);
    ASSERT_EQ(png.pixels.size(), exr.rgba.size() / 4 * 3);
    const auto srgb = [](double v) {
        v = std::clamp(v, 0.0, 1.0);
        return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
    };
    std::vector<double> codes;
    for (std::size_t i = 0; i < png.pixels.size(); ++i) {
        codes.push_back(std::abs(double(png.pixels[i]) - srgb(exr.rgba[i / 3 * 4 + i % 3])) * 255.0);
    }
    std::sort(codes.begin(), codes.end());
    const double p99 = codes[codes.size() * 99 / 100], worst = codes.back();
    std::printf("its .png against the sRGB curve of its EXR: %.2f codes at the 99th percentile, %.2f at most\n", p99, worst);
    EXPECT_LE(p99, 1.0);
    EXPECT_LE(worst, 2.0);
}
