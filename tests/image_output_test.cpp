/// @file image_output_test.cpp
/// @brief Images other than EXR (include/vdb_ewa/image_output.h) read back with OpenImageIO:
///        each 8-bit format holds the sRGB encoding of the beauty over black with its colour
///        space tag, .hdr the float values, and a bad path or extension fails with nothing
///        written.
#include "fixtures.h"
#include "image_read.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

/// A 16 x 8 image: grey columns from 0 to 2 (linear), opaque in the top half, alpha 0.5 and
/// premultiplied in the bottom half.
Image rampImage()
{
    Image image(16, 8);
    for (int x = 0; x < 16; ++x)
        for (int y = 0; y < 8; ++y) {
            const float a = y < 4 ? 1.0f : 0.5f;
            float* p = image.pixel(x, y);
            p[0] = p[1] = p[2] = a * 2.0f * float(x) / 15.0f;
            p[3] = a;
        }
    return image;
}

double srgbEncoded(double v)
{
    v = std::clamp(v, 0.0, 1.0);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

} // namespace

TEST(ImageOutput, FormatsAreChosenByExtension)
{
    EXPECT_EQ(imageFormatOf("a/b.EXR"), ImageFormat::Exr);
    EXPECT_EQ(imageFormatOf("shot.0001.png"), ImageFormat::Png);
    EXPECT_EQ(imageFormatOf("x.jpeg"), ImageFormat::Jpeg);
    EXPECT_EQ(imageFormatOf("x.JPG"), ImageFormat::Jpeg);
    EXPECT_EQ(imageFormatOf("x.tiff"), ImageFormat::Tiff);
    EXPECT_EQ(imageFormatOf("x.ppm"), ImageFormat::Ppm);
    EXPECT_EQ(imageFormatOf("x.hdr"), ImageFormat::Hdr);
    for (const char* none : {"x.bmp", "x.png.tmp", "png", ".png", "x"}) EXPECT_FALSE(imageFormatOf(none)) << none;
    EXPECT_EQ(imageFormatExtensions(), ".exr, .png, .jpg, .tif, .ppm or .hdr");
    EXPECT_FALSE(isDisplayReferred(ImageFormat::Exr));
    EXPECT_FALSE(isDisplayReferred(ImageFormat::Hdr));
    EXPECT_TRUE(isDisplayReferred(ImageFormat::Tiff));
}

TEST(ImageOutput, EightBitFormatsHoldTheDisplayTransformOfTheBeautyAndItsTag)
{
    // A linear Rec.709 working space through the plain sRGB view: 8-bit sRGB encoding of the
    // beauty over black (premultiplied colour), clamped.
    const Image image = rampImage();
    const ColorConfig config = ColorConfig::shipped();
    const ColorTransform toDisplay = ColorTransform::toDisplay(config, "Linear Rec.709 (sRGB)", "sRGB", "Un-tone-mapped");
    const std::string space = config.displayColorSpace("sRGB", "Un-tone-mapped");
    EXPECT_EQ(space, "sRGB - Display");
    TempDir dir;
    struct Case
    {
        const char* file;
        const char* tag;  // oiio:ColorSpace read back ("" for PPM: the format has none)
        double tolerance; // in 8-bit codes (JPEG is lossy)
    };
    for (const Case& c : {Case{"a.png", "sRGB", 0.51}, Case{"a.jpg", "sRGB", 6.0}, Case{"a.tif", "sRGB", 0.51}, Case{"a.ppm", "", 0.51}}) {
        SCOPED_TRACE(c.file);
        writeImage(image, dir.file(c.file), &toDisplay, {space, {{"vdb_ewa/input", "cloud.vdb"}}});
        const ImageFile r = readImageFile(dir.file(c.file));
        ASSERT_EQ(r.spec.width, 16);
        ASSERT_EQ(r.spec.height, 8);
        ASSERT_EQ(r.spec.nchannels, 3); // no alpha: the beauty over black, as vdb_render's
        EXPECT_EQ(r.spec.format, OIIO::TypeDesc::UINT8);
        if (*c.tag) {
            EXPECT_EQ(r.spec.get_string_attribute("oiio:ColorSpace"), c.tag);
        }
        double worst = 0.0;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 16; ++x)
                for (int ch = 0; ch < 3; ++ch) {
                    const double expected = 255.0 * srgbEncoded(image.pixel(x, y)[ch]);
                    worst = std::max(worst, std::abs(255.0 * r.pixels[std::size_t(3 * (y * 16 + x) + ch)] - expected));
                }
        EXPECT_LE(worst, c.tolerance);
    }
    const ImageFile png = readImageFile(dir.file("a.png"));
    EXPECT_EQ(png.spec.get_string_attribute("vdb_ewa/input"), "cloud.vdb"); // a PNG text chunk
}

TEST(ImageOutput, PreviewIsTheDisplayTransformOfTheBeauty)
{
    const Image image = rampImage();
    TempDir dir;
    const ColorConfig config = ColorConfig::shipped();
    writePreviewPng(image, ColorTransform::toDisplay(config, "Linear Rec.709 (sRGB)", "sRGB", "Un-tone-mapped"), dir.file("p.preview"));
    const ImageFile r = readImageFile(dir.file("p.preview"));
    EXPECT_EQ(std::string(r.spec.format == OIIO::TypeDesc::UINT8 ? "uint8" : "other"), "uint8");
    ASSERT_EQ(r.pixels.size(), std::size_t(16 * 8 * 3));
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) EXPECT_NEAR(255.0 * r.pixels[std::size_t(3 * (y * 16 + x))], 255.0 * srgbEncoded(image.pixel(x, y)[0]), 0.51);
}

TEST(ImageOutput, RadianceHdrHoldsTheFloatValues)
{
    Image image = rampImage();
    image.pixel(0, 0)[0] = -1.0f;                                   // RGBE holds no negative values
    image.pixel(1, 0)[1] = std::numeric_limits<float>::quiet_NaN(); // nor NaN
    TempDir dir;
    writeImage(image, dir.file("a.hdr"), nullptr, {"Linear Rec.709 (sRGB)", {}});
    const ImageFile r = readImageFile(dir.file("a.hdr"));
    ASSERT_EQ(r.spec.nchannels, 3);
    EXPECT_EQ(r.spec.format, OIIO::TypeDesc::FLOAT);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            for (int ch = 0; ch < 3; ++ch) {
                const float v = image.pixel(x, y)[ch];
                const double expected = std::isfinite(v) ? std::max(v, 0.0f) : 0.0;
                // RGBE: an 8-bit mantissa per channel, relative to the largest of the three.
                EXPECT_NEAR(r.pixels[std::size_t(3 * (y * 16 + x) + ch)], expected, 0.01 * expected + 1e-6) << x << "," << y << "," << ch;
            }
}

TEST(ImageOutput, BadPathsAndFormatsWriteNothing)
{
    const Image image = rampImage();
    const ColorConfig config = ColorConfig::shipped();
    const ColorTransform toDisplay = ColorTransform::toDisplay(config, "ACEScg", "sRGB", "ACES 1.0 - SDR Video");
    TempDir dir;
    EXPECT_THROW(writeImage(image, dir.file("a.bmp"), &toDisplay), ValueError);
    EXPECT_THROW(writeImage(image, dir.file("a.exr"), &toDisplay), ValueError);
    EXPECT_THROW(writeImage(image, dir.file("a.png"), nullptr), ValueError);    // 8-bit needs a display
    EXPECT_THROW(writeImage(image, dir.file("a.hdr"), &toDisplay), ValueError); // .hdr is scene-referred
    EXPECT_THROW(writeImage(image, dir.file("no/such/a.png"), &toDisplay), IoError);
    EXPECT_TRUE(std::filesystem::is_empty(dir.file("")));
}
