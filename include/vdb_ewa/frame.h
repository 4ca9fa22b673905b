/// @file frame.h
/// @brief A rendered frame: the beauty and the passes (AOVs) a compositor reads beside it.
/// @note Definitions in docs/output.md. Colour passes are in the renderer's working space,
///       premultiplied like the beauty; depths are camera-space depths (distance along the
///       viewing axis, OpenEXR's and RenderMan's convention), in world units.
#pragma once

#include <cstdint>
#include <vector>

#include "image.h"

namespace vdb_ewa {

/// Which passes to render beside the beauty (RGBA). Each costs time only when asked for.
struct PassRequest
{
    bool depth = false;         ///< Z: depth where the pixel's alpha first reaches 0.5
    bool transmittance = false; ///< RGB transmittance of the whole volume along the pixel
    bool shadow = false;        ///< light's shadow transmittance, composited like the beauty
    bool emission = false;      ///< the volume's own emission (RenderSettings::medium.emission) alone
    bool deep = false;          ///< one deep sample per non-empty slab
};

/// One deep sample: the medium between depths z and zBack on its own (not attenuated by the
/// samples in front), premultiplied colour, alpha = 1 - mean RGB transmittance of the span.
struct DeepSample
{
    float z = 0, zBack = 0;
    float r = 0, g = 0, b = 0, a = 0;
};

/// Deep pixels: the samples of pixel (x, y) are samples[offsets[i]] .. samples[offsets[i + 1] - 1],
/// i = y * width + x, sorted front to back and non-overlapping (OpenEXR's "tidy" state).
struct DeepImage
{
    int width = 0;
    int height = 0;
    std::vector<std::uint64_t> offsets; ///< width * height + 1
    std::vector<DeepSample> samples;

    std::uint64_t sampleCount(int x, int y) const
    {
        const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
        return offsets[i + 1] - offsets[i];
    }
};

struct Frame
{
    Image beauty;                      ///< premultiplied RGBA
    std::vector<float> depth;          ///< width * height; +inf where alpha never reaches 0.5
    std::vector<float> transmittance;  ///< width * height * 3 (RGB), empty unless requested
    std::vector<float> shadow;         ///< width * height * 3, premultiplied
    std::vector<float> emission;       ///< width * height * 3, premultiplied
    DeepImage deep;                    ///< empty unless requested
};

} // namespace vdb_ewa
