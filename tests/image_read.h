/// @file image_read.h
/// @brief Reading any image file back with OpenImageIO, as a lighter's viewer would.
#pragma once

#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace vdb_ewa::test {

struct ImageFile
{
    OIIO::ImageSpec spec;
    std::vector<float> pixels; ///< every channel, as floats (8-bit values in [0, 1])
};

/// @a path read with OpenImageIO (a failed read is a test failure, and an empty result).
inline ImageFile readImageFile(const std::string& path)
{
    ImageFile r;
    auto in = OIIO::ImageInput::open(path);
    EXPECT_TRUE(in) << path << ": " << OIIO::geterror();
    if (!in) return r;
    r.spec = in->spec();
    r.pixels.resize(std::size_t(r.spec.width) * std::size_t(r.spec.height) * std::size_t(r.spec.nchannels));
    EXPECT_TRUE(in->read_image(0, 0, 0, r.spec.nchannels, OIIO::TypeDesc::FLOAT, r.pixels.data())) << in->geterror();
    return r;
}

} // namespace vdb_ewa::test
