/// @file environment.cpp
#include <vdb_ewa/environment.h>

#include "output/image_codec.h"

#include <vdb_ewa/error.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace vdb_ewa {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// @a count directions spread evenly over the sphere (a Fibonacci lattice).
std::vector<Vec3d> fibonacciDirections(int count)
{
    std::vector<Vec3d> out(static_cast<std::size_t>(count));
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < count; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(count);
        const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
        out[std::size_t(i)] = Vec3d(r * std::cos(golden * i), y, r * std::sin(golden * i));
    }
    return out;
}

} // namespace

Vec3d latLongDirection(double u, double v)
{
    // OpenEXR (ImfEnvmap.h): latitude 0, longitude 0 is +Z; longitude pi/2 is +X.
    const double longitude = kPi * (1.0 - 2.0 * u), latitude = kPi * (0.5 - v);
    return Vec3d(std::sin(longitude) * std::cos(latitude), std::sin(latitude), std::cos(longitude) * std::cos(latitude));
}

std::vector<Light> environmentLights(const Image& latlong, int count, double intensity)
{
    if (latlong.width <= 0 || latlong.height <= 0) throw ValueError("--environment: the image is empty");
    if (count < 1 || std::size_t(count) > kMaxLights) {
        throw ValueError("--environment-lights must be in [1, " + std::to_string(kMaxLights) + "]");
    }
    if (!(intensity >= 0.0) || !std::isfinite(intensity)) throw ValueError("--environment-intensity must be finite and >= 0");
    const std::vector<Vec3d> centres = fibonacciDirections(count);
    std::vector<Vec3d> colour(centres.size(), Vec3d(0.0)), direction(centres.size(), Vec3d(0.0));
    const double du = 1.0 / latlong.width, dv = 1.0 / latlong.height;
    for (int y = 0; y < latlong.height; ++y) {
        const double v = (y + 0.5) * dv;
        // The pixel's solid angle: sin(theta) dtheta dphi.
        const double omega = std::sin(kPi * v) * (kPi * dv) * (2.0 * kPi * du);
        for (int x = 0; x < latlong.width; ++x) {
            const float* p = latlong.pixel(x, y);
            const Vec3d radiance(std::max(p[0], 0.0f), std::max(p[1], 0.0f), std::max(p[2], 0.0f));
            if (radiance.x + radiance.y + radiance.z == 0.0) continue;
            const Vec3d d = latLongDirection((x + 0.5) * du, v);
            std::size_t nearest = 0;
            for (std::size_t c = 1; c < centres.size(); ++c) {
                if (glm::dot(d, centres[c]) > glm::dot(d, centres[nearest])) nearest = c;
            }
            colour[nearest] += radiance * omega;
            direction[nearest] += (radiance.x + radiance.y + radiance.z) * omega * d;
        }
    }
    std::vector<Light> lights;
    for (std::size_t c = 0; c < centres.size(); ++c) {
        if (!(intensity * (colour[c].x + colour[c].y + colour[c].z) > 0.0)) continue;
        Light light;
        // A cell's light from opposite sides can cancel its mean direction: its centre then.
        light.direction = glm::length(direction[c]) > 1e-9 * (colour[c].x + colour[c].y + colour[c].z) ? glm::normalize(direction[c]) : centres[c];
        light.color = intensity * colour[c] / (4.0 * kPi);
        lights.push_back(light);
    }
    return lights;
}

Image readLatLongImage(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw IoError(path + ": no such image file");
    detail::CodecPixels pixels;
    const std::string error = detail::imageCodec().read(path, pixels, [&](int width, int height, int channels) {
        if (width <= 0 || height <= 0 || channels < 1) throw IoError(path + ": an empty image");
        if (std::abs(double(width) / double(height) - 2.0) > 0.02) {
            throw ValueError(path + ": a latitude-longitude image is twice as wide as high; this one is " + std::to_string(width) + "x" +
                             std::to_string(height));
        }
        if (double(width) * double(height) > 1e8) throw ValueError(path + ": larger than 100 megapixels");
    });
    if (!error.empty()) throw IoError(path + ": " + error);
    Image out(pixels.width, pixels.height);
    const std::size_t channels = std::size_t(pixels.channels);
    for (std::size_t i = 0; i < std::size_t(pixels.width) * std::size_t(pixels.height); ++i) {
        for (int c = 0; c < 3; ++c) {
            // Grey (and grey + alpha) images: every colour from the first channel.
            const float v = pixels.floats[i * channels + std::size_t(channels >= 3 ? c : 0)];
            out.rgba[4 * i + std::size_t(c)] = std::isfinite(v) && v > 0.0f ? v : 0.0f;
        }
        out.rgba[4 * i + 3] = 1.0f;
    }
    return out;
}

} // namespace vdb_ewa
