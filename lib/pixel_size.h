/// @file pixel_size.h
/// @brief Larger pixels (SplatOptions::pixelSize, docs/equations.md#larger-pixels): a fog
///        volume whose voxels look large is rendered through Camera::withPixelSize(s), one
///        sample an s x s block of pixels, and the frame interpolated bilinearly back onto the
///        image's pixels. Splatting at the larger pixels convolves each footprint with the
///        low-pass filter of the larger pixel (Eq. 33-35: the resampling filter of the coarser
///        raster), so the samples carry no alias. A voxel keeps spanning --supersample-span
///        samples or more, as sub-pixels give volumes seen small
///        (docs/equations.md#sub-pixel-samples).
#pragma once

#include <vdb_ewa/frame.h>
#include <vdb_ewa/render_settings.h>

namespace vdb_ewa {
namespace detail {

/// The pixel size for a frame whose median active voxel spans @a voxelPixels pixels (v): the
/// largest whole n <= settings.splat.pixelSize at which the voxel spans supersampleSpan
/// samples (v / n >= span: no bias of volumes seen small) and the larger pixel's filter, its
/// low-pass and the bilinear tent, adds at most pixelSizeBlur b of the kernel's variance (n^2
/// (lowpass + 1/6) <= b (kernelSigma v)^2: the finest detail at most sqrt(1 + b) wider);
/// +inf: the largest; 1 where unmeasured (0), for a deep image and with --iso surfaces (no
/// interpolation of samples or coverage). Whole sizes keep the samples on the same grid of
/// the image from frame to frame (a fractional size would move them as the voxels' size
/// changes: docs/equations.md#larger-pixels).
/// blend: where the bound reaches within kPixelSizeBlendShare of the next size (and the next
/// is allowed), the weight with which the frame at size + 1 is mixed in, rising from 0 to 1
/// across that share: no jump where a camera's move changes the size (docs/equations.md#larger-pixels).
struct PixelSize
{
    int size = 1;
    double blend = 0.0;
};
PixelSize choosePixelSize(const RenderSettings& settings, double voxelPixels, const PassRequest& passes);

/// The last part of the way from one pixel size to the next over which the next fades in.
inline constexpr double kPixelSizeBlendShare = 0.25;

/// @a big, rendered through camera.withPixelSize(@a size), brought back to the @a width x
/// @a height image: colour, alpha, transmittance and the colour passes interpolated
/// bilinearly between the four larger pixels' centres around each pixel's centre (pixel x's
/// centre x + 1/2 lies at (x + 1/2) / size + 1/2 of the larger pixels' centres); Z, the
/// nearest larger pixel's (a depth has no average across an edge). @a size 1: @a big as it is.
Frame upsampled(Frame big, double size, int width, int height, const PassRequest& passes);

} // namespace detail
} // namespace vdb_ewa
