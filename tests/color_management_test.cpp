/// @file color_management_test.cpp
/// @brief The shipped OCIO config against colour science computed here, independently of
///        OpenColorIO (primaries -> XYZ matrices, Bradford adaptation, the sRGB curve); the
///        config precedence and its fallbacks; chromaticities.
#include "fixtures.h"

#include <vdb_ewa/color_management.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// RGB -> XYZ of primaries and white given as xy (the SMPTE RP 177 construction).
Mat3d rgbToXyz(const Vec2d& r, const Vec2d& g, const Vec2d& b, const Vec2d& w)
{
    auto xyz = [](const Vec2d& p) { return Vec3d(p.x / p.y, 1.0, (1.0 - p.x - p.y) / p.y); };
    const Mat3d primaries(xyz(r), xyz(g), xyz(b)); // columns
    const Vec3d scale = glm::inverse(primaries) * xyz(w);
    return Mat3d(primaries[0] * scale.x, primaries[1] * scale.y, primaries[2] * scale.z);
}

/// Bradford chromatic adaptation from white @a from to white @a to (XYZ -> XYZ).
Mat3d bradford(const Vec2d& from, const Vec2d& to)
{
    const Mat3d m = mat3FromRows({0.8951, 0.2664, -0.1614}, {-0.7502, 1.7135, 0.0367}, {0.0389, -0.0685, 1.0296});
    auto xyz = [](const Vec2d& p) { return Vec3d(p.x / p.y, 1.0, (1.0 - p.x - p.y) / p.y); };
    const Vec3d a = m * xyz(from), b = m * xyz(to);
    const Mat3d d(Vec3d(b.x / a.x, 0, 0), Vec3d(0, b.y / a.y, 0), Vec3d(0, 0, b.z / a.z));
    return glm::inverse(m) * d * m;
}

const Vec2d kAcesWhite{0.32168, 0.33767}, kD65{0.3127, 0.3290};

/// ACEScg -> linear Rec.709, from the published primaries (S-2014-004, ITU-R BT.709).
Mat3d acescgToRec709()
{
    const Mat3d ap1 = rgbToXyz({0.713, 0.293}, {0.165, 0.830}, {0.128, 0.044}, kAcesWhite);
    const Mat3d rec709 = rgbToXyz({0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}, kD65);
    return glm::inverse(rec709) * bradford(kAcesWhite, kD65) * ap1;
}

/// IEC 61966-2-1 encoding.
double srgbEncode(double v)
{
    v = std::clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

void expectNear3(const Vec3d& a, const Vec3d& b, double tolerance, const std::string& what)
{
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tolerance) << what << " channel " << c;
}

/// Sets an environment variable for the scope of a test (each test runs in its own process
/// under ctest; the old value is restored for gtest's in-process runs).
class ScopedEnv
{
public:
    ScopedEnv(const char* name, const char* value) : mName(name)
    {
        if (const char* old = std::getenv(name)) mOld = old;
        if (value) ::setenv(name, value, 1);
        else ::unsetenv(name);
    }
    ~ScopedEnv()
    {
        if (mOld) ::setenv(mName.c_str(), mOld->c_str(), 1);
        else ::unsetenv(mName.c_str());
    }

private:
    std::string mName;
    std::optional<std::string> mOld;
};

std::string shippedConfigText()
{
    std::ifstream in(std::string(VDB_EWA_SOURCE_DIR) + "/share/ocio/config.ocio");
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

} // namespace

TEST(ColorManagement, ShippedConfigHasTheRolesDisplaysAndViews)
{
    const ColorConfig config = ColorConfig::shipped();
    EXPECT_EQ(config.roleSpace("scene_linear"), "ACEScg");
    EXPECT_EQ(config.roleSpace("aces_interchange"), "ACES2065-1");
    EXPECT_EQ(config.colorSpace("lin_rec709"), "Linear Rec.709 (sRGB)"); // alias
    EXPECT_EQ(config.colorSpace("scene_linear"), "ACEScg");              // role
    EXPECT_TRUE(config.isData("Raw"));
    EXPECT_FALSE(config.isData("ACEScg"));
    EXPECT_EQ(config.defaultDisplay(), "sRGB");
    // The plain sRGB curve by default (8-bit dailies hold the EXR's values, as a comp without
    // an ACES config shows them); the ACES view one option away.
    EXPECT_EQ(config.defaultView("sRGB"), "Un-tone-mapped");
    EXPECT_NO_THROW(config.checkDisplayView("sRGB", "ACES 1.0 - SDR Video"));
    EXPECT_TRUE(config.isShipped());
    EXPECT_FALSE(ColorConfig::fromString(shippedConfigText()).isShipped()) << "the same text from elsewhere is the user's config";
    EXPECT_THROW(config.checkDisplayView("sRGB", "Filmic"), ValueError);
    EXPECT_THROW(config.checkDisplayView("P3", "Un-tone-mapped"), ValueError);
    try {
        config.colorSpace("Linear P3");
        FAIL() << "unknown colour space accepted";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("ACEScg"), std::string::npos) << "the message lists the spaces: " << e.what();
    }
}

TEST(ColorManagement, GreyAndSaturatedColourMatchIndependentMatrices)
{
    const ColorConfig config = ColorConfig::shipped();
    const ColorTransform toRec709 = ColorTransform::between(config, "ACEScg", "Linear Rec.709 (sRGB)");
    const Mat3d m = acescgToRec709();
    for (const Vec3d& c : {Vec3d(0.18), Vec3d(0.8, 0.1, 0.05), Vec3d(0.02, 0.6, 0.9), Vec3d(1, 0, 0)}) {
        expectNear3(toRec709.apply(c), m * c, 2e-6 + 2e-6 * glm::length(m * c), "ACEScg -> Linear Rec.709");
    }
    // 18% grey stays grey in every linear space with a white-preserving adaptation.
    expectNear3(toRec709.apply(Vec3d(0.18)), Vec3d(0.18), 1e-6, "grey");
    // The round trip is the identity.
    const ColorTransform back = ColorTransform::between(config, "Linear Rec.709 (sRGB)", "ACEScg");
    expectNear3(back.apply(toRec709.apply(Vec3d(0.8, 0.1, 0.05))), Vec3d(0.8, 0.1, 0.05), 1e-5, "round trip");
    EXPECT_TRUE(ColorTransform::between(config, "ACEScg", "scene_linear").isNoOp());
}

TEST(ColorManagement, DisplayViewsMatchTheSrgbCurveAndPublishedAcesValues)
{
    const ColorConfig config = ColorConfig::shipped();
    const Mat3d m = acescgToRec709();
    // The plain sRGB view: the sRGB encoding of the Rec.709 values, clamped to [0, 1].
    const ColorTransform plain = ColorTransform::toDisplay(config, "ACEScg", "sRGB", "Un-tone-mapped");
    for (const Vec3d& c : {Vec3d(0.18), Vec3d(0.8, 0.1, 0.05), Vec3d(0.001), Vec3d(4.0)}) {
        const Vec3d lin = m * c;
        expectNear3(plain.apply(c), Vec3d(srgbEncode(lin.x), srgbEncode(lin.y), srgbEncode(lin.z)), 3e-5, "Un-tone-mapped");
    }
    // ACES 1.0 SDR video (RRT + sRGB 100-nit ODT). Neutral axis re-derived from the ACES CTL
    // (aces-dev 1.0.3 segmented splines): 0.18 -> 0.3559543; ACEScentral's published 1.0 -> 0.812.
    const ColorTransform aces = ColorTransform::toDisplay(config, "ACEScg", "sRGB", "ACES 1.0 - SDR Video");
    expectNear3(aces.apply(Vec3d(0.18)), Vec3d(0.3559543), 1e-4, "ACES SDR 18% grey");
    expectNear3(aces.apply(Vec3d(1.0)), Vec3d(0.812), 1e-3, "ACES SDR 1.0");
    // Saturated colours stay in [0, 1] and keep their hue order.
    const Vec3d red = aces.apply(Vec3d(0.8, 0.1, 0.05));
    EXPECT_GT(red.x, red.y);
    EXPECT_GT(red.y, -1e-6);
    EXPECT_LE(red.x, 1.0);
}

TEST(ColorManagement, ConfigPrecedenceAndFallbacks)
{
    TempDir dir;
    const std::string good = dir.file("studio.ocio"), other = dir.file("other.ocio"), broken = dir.file("broken.ocio");
    for (const std::string& p : {good, other}) std::ofstream(p) << shippedConfigText();
    std::ofstream(broken) << "ocio_profile_version: 2\nroles: {scene_linear: nowhere}\ncolorspaces: [\n";
    // Valid YAML whose default view needs a LUT file that is not there.
    const std::string missingLut = dir.file("missing_lut.ocio");
    std::string text = shippedConfigText();
    const std::string builtin = "!<BuiltinTransform> {style: DISPLAY - CIE-XYZ-D65_to_sRGB}";
    ASSERT_NE(text.find(builtin), std::string::npos);
    text.replace(text.find(builtin), builtin.size(), "!<FileTransform> {src: no_such_lut.spi3d, interpolation: tetrahedral}");
    text.replace(text.find("search_path: \"\""), 15, "search_path: luts");
    std::ofstream(missingLut) << text;

    std::vector<std::string> warnings;
    {
        ScopedEnv env("OCIO", other.c_str());
        EXPECT_EQ(ColorConfig::resolve(good, warnings).origin(), good) << "the explicit config comes first";
        EXPECT_EQ(ColorConfig::resolve("", warnings).origin(), other) << "then $OCIO";
        EXPECT_TRUE(warnings.empty());
        EXPECT_EQ(ColorConfig::resolve(broken, warnings).origin(), other) << "a broken explicit config falls to $OCIO";
        ASSERT_EQ(warnings.size(), 1u);
        EXPECT_NE(warnings[0].find(broken), std::string::npos) << warnings[0];
    }
    warnings.clear();
    {
        ScopedEnv env("OCIO", nullptr);
        EXPECT_EQ(ColorConfig::resolve("", warnings).origin(), ColorConfig::shipped().origin()) << "then the shipped config";
        EXPECT_TRUE(warnings.empty());
    }
    for (const std::string& bad : {broken, missingLut, dir.file("missing.ocio"), std::string("ocio://default")}) {
        warnings.clear();
        ScopedEnv env("OCIO", bad.c_str());
        EXPECT_EQ(ColorConfig::resolve("", warnings).origin(), ColorConfig::shipped().origin()) << bad;
        ASSERT_EQ(warnings.size(), 1u) << bad;
        EXPECT_NE(warnings[0].find("$OCIO"), std::string::npos) << warnings[0];
        EXPECT_NE(warnings[0].find(bad), std::string::npos) << warnings[0];
        EXPECT_EQ(warnings[0].find('\n'), std::string::npos) << "one line: " << warnings[0];
    }
    EXPECT_NE(warnings[0].find("2.2"), std::string::npos) << "an ocio:// URI names the OCIO version it needs: " << warnings[0];
    EXPECT_THROW(ColorConfig::fromString("not a config"), ValueError);
    EXPECT_EQ(ColorConfig::fromString(shippedConfigText()).roleSpace("scene_linear"), "ACEScg");
}

TEST(ColorManagement, ColorInteropIds)
{
    const ColorConfig config = ColorConfig::shipped();
    EXPECT_EQ(colorInteropIdOf(config, "ACEScg"), "lin_ap1_scene");
    EXPECT_EQ(colorInteropIdOf(config, "ACES2065-1"), "lin_ap0_scene");
    EXPECT_EQ(colorInteropIdOf(config, "lin_srgb"), "lin_rec709_scene"); // by alias
    EXPECT_EQ(colorInteropIdOf(config, "sRGB - Texture"), "srgb_rec709_scene");
    EXPECT_EQ(colorInteropIdOf(config, "Raw"), "data");
    EXPECT_EQ(colorInteropIdOf(config, "ACEScct"), "") << "a space without an identifier gets none";
    EXPECT_EQ(colorInteropIdOf(config, "no such space"), "");
}

TEST(ColorManagement, Chromaticities)
{
    const ColorConfig config = ColorConfig::shipped();
    std::string how;
    const auto ap1 = chromaticitiesOf(config, "ACEScg", &how);
    ASSERT_TRUE(ap1);
    EXPECT_EQ(ap1->red, Vec2d(0.713, 0.293));
    EXPECT_EQ(ap1->white, kAcesWhite);
    EXPECT_NE(how.find("published"), std::string::npos);
    const auto rec709 = chromaticitiesOf(config, "lin_srgb");
    ASSERT_TRUE(rec709);
    EXPECT_EQ(rec709->green, Vec2d(0.30, 0.60));
    // A space outside the table is derived through the config's CIE XYZ D65 interchange.
    const auto derived = chromaticitiesOf(config, "sRGB - Texture", &how);
    ASSERT_TRUE(derived) << how;
    EXPECT_NE(how.find("derived"), std::string::npos) << how;
    const Vec2d expected[4] = {{0.64, 0.33}, {0.30, 0.60}, {0.15, 0.06}, kD65};
    const Vec2d got[4] = {derived->red, derived->green, derived->blue, derived->white};
    for (int i = 0; i < 4; ++i) {
        EXPECT_NEAR(got[i].x, expected[i].x, 2e-4) << i;
        EXPECT_NEAR(got[i].y, expected[i].y, 2e-4) << i;
    }
    EXPECT_FALSE(chromaticitiesOf(config, "Raw")) << "data spaces have no chromaticities";
}
