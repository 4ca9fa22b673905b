/// @file pixel_size.cpp
#include "pixel_size.h"

#include "support/blank_frame.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace vdb_ewa {
namespace detail {
namespace {

/// The variance of the bilinear tent, per axis, in larger pixels^2 (a triangle of half-width 1).
constexpr double kTentVariance = 1.0 / 6.0;

/// One axis of the interpolation: pixel x reads larger pixels i0 and i0 + 1 with weights 1 - t
/// and t, and its Z from the nearer of them, near.
struct Taps
{
    std::vector<int> i0, near;
    std::vector<float> t;
};

Taps taps(int pixels, double size, int bigPixels)
{
    Taps a;
    a.i0.resize(std::size_t(pixels));
    a.near.resize(std::size_t(pixels));
    a.t.resize(std::size_t(pixels));
    for (int x = 0; x < pixels; ++x) {
        const double u = (double(x) + 0.5) / size + 0.5; // in the larger pixels' centres (Camera::withPixelSize)
        const int i = std::clamp(int(std::floor(u)), 0, bigPixels - 2); // u >= 1/2 and <= bigPixels - 1
        a.i0[std::size_t(x)] = i;
        a.t[std::size_t(x)] = float(std::clamp(u - double(i), 0.0, 1.0));
        a.near[std::size_t(x)] = a.t[std::size_t(x)] < 0.5f ? i : i + 1;
    }
    return a;
}

} // namespace

PixelSize choosePixelSize(const RenderSettings& settings, double voxelPixels, const PassRequest& passes)
{
    PixelSize p;
    const int most = settings.splat.pixelSize;
    // Deep samples and --iso surfaces' coverage have no interpolation: every pixel.
    if (most <= 1 || passes.deep || !std::isnan(settings.surface.iso) || !(voxelPixels > 0.0)) return p;
    const SplatOptions& o = settings.splat;
    const double spanned = voxelPixels / o.supersampleSpan;                                      // Jensen: span samples a voxel
    const double blurred = o.kernelSigma * voxelPixels * std::sqrt(o.pixelSizeBlur / (o.lowpass + kTentVariance)); // the filter's share of the kernel's variance
    const double bound = std::min(spanned, blurred);                                            // +inf: most
    p.size = int(std::clamp(std::floor(bound), 1.0, double(most)));
    const double fadeFrom = double(p.size + 1) - kPixelSizeBlendShare;
    if (p.size < most && bound > fadeFrom) p.blend = std::min(1.0, (bound - fadeFrom) / kPixelSizeBlendShare);
    return p;
}

Frame upsampled(Frame big, double size, int width, int height, const PassRequest& passes)
{
    if (size <= 1.0) return big;
    const int bigWidth = big.beauty.width, bigHeight = big.beauty.height;
    Frame out = blankFrame(width, height, passes);
    const Taps tx = taps(width, size, bigWidth), ty = taps(height, size, bigHeight);
    const std::size_t bw = std::size_t(bigWidth);
    // A plane of @a channels interleaved floats a pixel, row y: bilinear in x and y.
    const auto row = [&](const std::vector<float>& in, std::vector<float>& to, int channels, int y) {
        const std::size_t c = std::size_t(channels), r0 = std::size_t(ty.i0[std::size_t(y)]) * bw, r1 = r0 + bw;
        const float v = ty.t[std::size_t(y)];
        float* dst = to.data() + std::size_t(y) * std::size_t(width) * c;
        for (int x = 0; x < width; ++x) {
            const std::size_t a = std::size_t(tx.i0[std::size_t(x)]), b = a + 1;
            const float u = tx.t[std::size_t(x)];
            for (std::size_t k = 0; k < c; ++k) {
                const float top = in[(r0 + a) * c + k] + u * (in[(r0 + b) * c + k] - in[(r0 + a) * c + k]);
                const float bottom = in[(r1 + a) * c + k] + u * (in[(r1 + b) * c + k] - in[(r1 + a) * c + k]);
                dst[std::size_t(x) * c + k] = top + v * (bottom - top);
            }
        }
    };
    tbb::parallel_for(0, height, [&](int y) {
        row(big.beauty.rgba, out.beauty.rgba, 4, y);
        if (passes.transmittance) row(big.transmittance, out.transmittance, 3, y);
        if (passes.shadow) row(big.shadow, out.shadow, 3, y);
        if (passes.emission) row(big.emission, out.emission, 3, y);
        if (passes.depth) {
            const std::size_t by = std::size_t(ty.near[std::size_t(y)]) * bw;
            for (int x = 0; x < width; ++x) {
                out.depth[std::size_t(y) * std::size_t(width) + std::size_t(x)] = big.depth[by + std::size_t(tx.near[std::size_t(x)])];
            }
        }
    });
    return out;
}

} // namespace detail
} // namespace vdb_ewa
