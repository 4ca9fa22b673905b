/// @file exr_output.cpp
/// @brief OpenEXR I/O (docs/output.md). Writes go through detail::writeAtomically.
#include <vdb_ewa/exr_output.h>

#include "output/atomic_write.h"
#include "output/exr_header.h"
#include "output/exr_zip_writer.h"
#include "support/huge_page_allocator.h"

#include <vdb_ewa/error.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineOutputFile.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <Imath/half.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <deque>
#include <string>
#include <system_error>
#include <thread>

namespace vdb_ewa {
namespace {

Imf::Compression imfCompression(ExrCompression c)
{
    switch (c) {
    case ExrCompression::None: return Imf::NO_COMPRESSION;
    case ExrCompression::Rle: return Imf::RLE_COMPRESSION;
    case ExrCompression::Zip: return Imf::ZIP_COMPRESSION;
    case ExrCompression::Zips: return Imf::ZIPS_COMPRESSION;
    case ExrCompression::Piz: return Imf::PIZ_COMPRESSION;
    case ExrCompression::Dwaa: return Imf::DWAA_COMPRESSION;
    case ExrCompression::Dwab: return Imf::DWAB_COMPRESSION;
    }
    return Imf::ZIP_COMPRESSION;
}

Imf::PixelType imfType(ExrPixelType t) { return t == ExrPixelType::Half ? Imf::HALF : Imf::FLOAT; }

/// 4x4 matrix (column-vector convention, rows given) -> OpenEXR's row-vector matrix (its
/// transpose), row by row as Imath's M44f holds it.
std::array<float, 16> rowVectorMatrix(const double m[4][4])
{
    std::array<float, 16> out;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) out[std::size_t(4 * i + j)] = float(m[j][i]);
    return out;
}

Imath::M44f imathMatrix(const std::array<float, 16>& m)
{
    Imath::M44f out;
    std::copy(m.begin(), m.end(), &out[0][0]);
    return out;
}

/// worldToCamera, worldToNDC and the screen window (OpenEXR's definitions: camera space
/// x right, y up, z forward; NDC (0, 0) top left, (1, 1) bottom right of the display window).
void addCameraAttributes(detail::ExrHeader& header, const Camera& camera)
{
    const Mat3d& R = camera.cameraFromWorld(); // rows: right, down, forward
    const Vec3d eye = camera.eye();
    double view[4][4] = {}; // our camera space t = R (p - eye), as a 4x4
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) view[r][c] = R[c][r];
        const Vec3d row(R[0][r], R[1][r], R[2][r]);
        view[r][3] = -glm::dot(row, eye);
    }
    view[3][3] = 1.0;

    double toNdc[4][4] = {};
    const double w = camera.width(), h = camera.height(), s = camera.focalPixels();
    if (camera.projection() == Projection::Perspective) {
        // (s t0 / t2 + w / 2) / w, (s t1 / t2 + h / 2) / h, z = 1 / t2 (homogeneous w = t2).
        const double p[4][4] = {{s / w, 0, 0.5, 0}, {0, s / h, 0.5, 0}, {0, 0, 0, 1}, {0, 0, 1, 0}};
        std::copy(&p[0][0], &p[0][0] + 16, &toNdc[0][0]);
        header.screenWindowWidth = float(w / s); // image width on the plane z = 1
    } else {
        const double p[4][4] = {{s / w, 0, 0, 0.5}, {0, s / h, 0, 0.5}, {0, 0, 1, 0}, {0, 0, 0, 1}};
        std::copy(&p[0][0], &p[0][0] + 16, &toNdc[0][0]);
        header.screenWindowWidth = float(w / s); // frame width in world units
    }
    double ndc[4][4] = {}, cam[4][4] = {};
    const double flip[3] = {1.0, -1.0, 1.0}; // our t1 points down, OpenEXR's y up
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            cam[r][c] = (r < 3 ? flip[r] : 1.0) * view[r][c];
            for (int k = 0; k < 4; ++k) ndc[r][c] += toNdc[r][k] * view[k][c];
        }
    header.worldToCamera = rowVectorMatrix(cam);
    header.worldToNdc = rowVectorMatrix(ndc);
}

/// OpenEXR's C++ header of @a values (the zip writer sets the same in exr_zip_writer.cpp).
Imf::Header imfHeader(const detail::ExrHeader& values, int zipLevel)
{
    Imf::Header header(values.width, values.height);
    header.compression() = imfCompression(values.compression);
    header.zipCompressionLevel() = zipLevel;
    if (values.chromaticities) {
        const Chromaticities& c = *values.chromaticities;
        auto v = [](const Vec2d& p) { return Imath::V2f(float(p.x), float(p.y)); };
        Imf::addChromaticities(header, Imf::Chromaticities(v(c.red), v(c.green), v(c.blue), v(c.white)));
    }
    if (values.worldToCamera && values.worldToNdc) {
        Imf::addWorldToCamera(header, imathMatrix(*values.worldToCamera));
        Imf::addWorldToNDC(header, imathMatrix(*values.worldToNdc));
    }
    header.screenWindowWidth() = values.screenWindowWidth;
    for (const auto& [key, value] : values.strings) header.insert(key, Imf::StringAttribute(value));
    return header;
}

/// A frame's flat planes: R, G, B, A, then Z and the passes' layers it holds.
std::vector<detail::ExrPlane> flatPlanes(const Frame& frame, bool halfColour)
{
    std::vector<detail::ExrPlane> planes;
    auto add = [&](const std::vector<float>& values, std::size_t stride, const std::vector<std::string>& names, bool half) {
        for (std::size_t c = 0; c < names.size(); ++c) planes.push_back({names[c], values.data() + c, stride, half});
    };
    add(frame.beauty.rgba, 4, {"R", "G", "B", "A"}, halfColour);
    if (!frame.depth.empty()) add(frame.depth, 1, {"Z"}, false);
    const std::pair<const char*, const std::vector<float>*> passes[] = {
        {"transmittance", &frame.transmittance}, {"shadow", &frame.shadow}, {"emission", &frame.emission}};
    for (const auto& [layer, values] : passes) {
        const std::string l(layer);
        if (!values->empty()) add(*values, 3, {l + ".R", l + ".G", l + ".B"}, halfColour);
    }
    return planes;
}

/// OpenEXR's frame buffer of @a planes, their channels added to @a header: float planes as they
/// are, half planes converted into @a halves (OpenEXR's OutputFile does not convert pixel types).
Imf::FrameBuffer imfFrameBuffer(const std::vector<detail::ExrPlane>& planes, Imf::Header& header, std::size_t width,
    std::size_t pixels, std::deque<std::vector<half>>& halves)
{
    Imf::FrameBuffer fb;
    for (const detail::ExrPlane& p : planes) {
        const Imf::PixelType type = p.half ? Imf::HALF : Imf::FLOAT;
        header.channels().insert(p.name, Imf::Channel(type));
        if (!p.half) {
            const std::size_t xStride = p.stride * sizeof(float);
            fb.insert(p.name, Imf::Slice(type, reinterpret_cast<char*>(const_cast<float*>(p.values)), xStride, xStride * width));
            continue;
        }
        std::vector<half>& h = halves.emplace_back();
        detail::assignAdvised(h, pixels, half()); // 2-8 MB at 1080p: huge pages where they cannot stall
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t i = r.begin(); i < r.end(); ++i) h[i] = detail::toHalf(p.values[i * p.stride]);
        });
        fb.insert(p.name, Imf::Slice(type, reinterpret_cast<char*>(h.data()), sizeof(half), sizeof(half) * width));
    }
    return fb;
}

} // namespace

namespace detail {

ExrHeader exrHeader(int width, int height, const ExrOptions& options)
{
    ExrHeader header;
    header.width = width;
    header.height = height;
    header.compression = options.compression;
    header.chromaticities = options.chromaticities;
    if (options.camera) addCameraAttributes(header, *options.camera);
    header.strings = options.attributes;
    return header;
}

} // namespace detail

bool validForDeep(ExrCompression c)
{
    // OpenEXR 3.1 rejects ZIP (16-line blocks) for deep scanline files; ZIPS is per line.
    return c == ExrCompression::None || c == ExrCompression::Rle || c == ExrCompression::Zips;
}

void writeExr(const Frame& frame, const std::string& path, const ExrOptions& options)
{
    const Image& beauty = frame.beauty;
    const detail::ExrHeader values = detail::exrHeader(beauty.width, beauty.height, options);
    const std::vector<detail::ExrPlane> planes = flatPlanes(frame, options.colorType == ExrPixelType::Half);
    detail::writeAtomically(path, "EXR", [&](const std::string& tmp) {
        // Zip and zips, the default and vdb_render's: deflated by libdeflate (exr_zip_writer.h).
        if (options.compression == ExrCompression::Zip || options.compression == ExrCompression::Zips) {
            detail::writeZipExr(tmp, values, planes, options.zipLevel);
            return;
        }
        Imf::Header header = imfHeader(values, options.zipLevel);
        std::deque<std::vector<half>> halves;
        const Imf::FrameBuffer fb = imfFrameBuffer(planes, header, std::size_t(beauty.width),
            std::size_t(beauty.width) * std::size_t(beauty.height), halves);
        Imf::OutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(beauty.height);
    });
}

void writeDeepExr(const DeepImage& deep, const std::string& path, const ExrOptions& options)
{
    if (!validForDeep(options.compression)) {
        throw ValueError(path + ": deep EXR files take none, rle, zips or zip compression only");
    }
    detail::writeAtomically(path, "deep EXR", [&](const std::string& tmp) {
        Imf::Header header = imfHeader(detail::exrHeader(deep.width, deep.height, options), options.zipLevel);
        header.setType(Imf::DEEPSCANLINE);
        Imf::addDeepImageState(header, Imf::DIS_TIDY);
        const std::size_t pixels = std::size_t(deep.width) * std::size_t(deep.height);
        std::vector<unsigned> counts(pixels);
        for (std::size_t i = 0; i < pixels; ++i) counts[i] = unsigned(deep.offsets[i + 1] - deep.offsets[i]);
        Imf::DeepFrameBuffer fb;
        fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(unsigned),
            sizeof(unsigned) * std::size_t(deep.width)));
        // Colour as half RGBA per sample when asked (OpenEXR does not convert pixel types).
        const Imf::PixelType colour = imfType(options.colorType);
        std::vector<half> halves;
        if (colour == Imf::HALF) {
            halves.resize(deep.samples.size() * 4);
            for (std::size_t i = 0; i < deep.samples.size(); ++i) {
                const DeepSample& d = deep.samples[i];
                const float v[4] = {d.r, d.g, d.b, d.a};
                std::transform(v, v + 4, &halves[4 * i], detail::toHalf);
            }
        }
        // One array of per-pixel pointers per channel, each at the pixel's first sample.
        struct Channel
        {
            const char* name;
            Imf::PixelType type;
            char* base;             ///< the channel's value in sample 0
            std::size_t sampleStride;
        };
        char* samples = reinterpret_cast<char*>(const_cast<DeepSample*>(deep.samples.data()));
        char* rgba = reinterpret_cast<char*>(halves.data());
        std::vector<Channel> channels = {{"Z", Imf::FLOAT, samples + offsetof(DeepSample, z), sizeof(DeepSample)},
            {"ZBack", Imf::FLOAT, samples + offsetof(DeepSample, zBack), sizeof(DeepSample)}};
        // R, G, B, A: the half copy (4 per sample), or DeepSample's consecutive floats r, g, b, a.
        static_assert(offsetof(DeepSample, a) == offsetof(DeepSample, r) + 3 * sizeof(float));
        const char* colourNames[4] = {"R", "G", "B", "A"};
        for (std::size_t c = 0; c < 4; ++c) {
            channels.push_back(colour == Imf::HALF
                    ? Channel{colourNames[c], colour, rgba + c * sizeof(half), 4 * sizeof(half)}
                    : Channel{colourNames[c], colour, samples + offsetof(DeepSample, r) + c * sizeof(float), sizeof(DeepSample)});
        }
        std::vector<std::vector<char*>> pointers;
        for (const Channel& c : channels) {
            header.channels().insert(c.name, Imf::Channel(c.type));
            std::vector<char*>& p = pointers.emplace_back(pixels);
            for (std::size_t i = 0; i < pixels; ++i) p[i] = c.base + deep.offsets[i] * c.sampleStride;
            fb.insert(c.name, Imf::DeepSlice(c.type, reinterpret_cast<char*>(p.data()), sizeof(char*),
                                  sizeof(char*) * std::size_t(deep.width), c.sampleStride));
        }
        Imf::DeepScanLineOutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(deep.height);
    });
}

void writeExr(const Image& image, const std::string& path,
    const std::vector<std::pair<std::string, std::string>>& attributes)
{
    Frame frame;
    frame.beauty = image; // a copy; this overload serves tests and tools, not the render path
    ExrOptions options;
    options.colorType = ExrPixelType::Float;
    options.attributes = attributes;
    writeExr(frame, path, options);
}

void setExrThreadsProcessWide(int threads)
{
    // More compression threads than cores gain nothing, and each reserves a stack: --threads 1024
    // under a farm's address-space limit failed to start them.
    const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
    const int count = threads > 0 ? std::min(threads, cores) : cores;
    try {
        Imf::setGlobalThreadCount(count);
    } catch (const std::system_error& e) {
        throw BudgetError("--threads " + std::to_string(threads) + ": the system could not start " + std::to_string(count) +
                          " EXR compression threads (" + e.what() + ")");
    }
}

Image readExr(const std::string& path)
{
    try {
        Imf::InputFile file(path.c_str());
        const Imath::Box2i dw = file.header().dataWindow();
        Image image(dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1);
        const std::size_t xStride = 4 * sizeof(float), yStride = xStride * std::size_t(image.width);
        char* base = reinterpret_cast<char*>(image.rgba.data()) -
                     (std::ptrdiff_t(dw.min.x) * std::ptrdiff_t(xStride) + std::ptrdiff_t(dw.min.y) * std::ptrdiff_t(yStride));
        const char* names[4] = {"R", "G", "B", "A"};
        Imf::FrameBuffer fb;
        for (int c = 0; c < 4; ++c) {
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xStride, yStride, 1, 1, c == 3 ? 1.0 : 0.0));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return image;
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read EXR (" + std::string(e.what()) + ")");
    }
}

} // namespace vdb_ewa
