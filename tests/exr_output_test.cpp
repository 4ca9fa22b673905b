/// @file exr_output_test.cpp
/// @brief Files as a compositor reads them, read back with OpenEXR: every channel and
///        attribute, each compression, deep files flattened, writes that fail without
///        touching an existing file, and the zip writer's chunks. Other formats: image_output_test.cpp.
#include "fixtures.h"

#include "output/atomic_write.h"
#include "output/exr_header.h"
#include "output/exr_zip_writer.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepScanLineInputFile.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/openexr.h>
#include <zlib.h>

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>

using namespace vdb_ewa;
using namespace vdb_ewa::test;

namespace {

std::string slurp(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// Every file in the folder of @a path (to catch stray temporary files).
std::vector<std::string> folderContents(const std::string& path)
{
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(path).parent_path())) {
        names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

/// One float plane of a flat EXR.
std::vector<float> readChannel(const std::string& path, const std::string& name)
{
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
    std::vector<float> values(std::size_t(w) * std::size_t(h));
    Imf::FrameBuffer fb;
    fb.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data()), sizeof(float), sizeof(float) * std::size_t(w)));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return values;
}

struct CloudView
{
    GridSource cloud = makeSampleGrid(SampleGrid::Cloud, 0.05);
    Camera camera = cloudCamera(cloud, 64, 48);
};

Frame renderAll(const CloudView& scene, bool deep = false)
{
    PassRequest p;
    p.depth = p.transmittance = p.shadow = p.emission = !deep;
    p.deep = deep;
    RenderSettings s;
    s.medium.emission = Vec3d(0.1, 0.05, 0.0);
    s.splat.supersample = 1; // a deep image is composited at one sample a pixel: the flat one too, to compare
    return Renderer(s).renderFrame(scene.cloud, scene.camera, p);
}

} // namespace

TEST(ExrOutput, EveryChannelAndAttributeReadsBack)
{
    const CloudView scene;
    const Frame frame = renderAll(scene);
    TempDir dir;
    for (const ExrPixelType type : {ExrPixelType::Half, ExrPixelType::Float}) {
        const std::string path = dir.file(type == ExrPixelType::Half ? "half.exr" : "float.exr");
        ExrOptions options;
        options.colorType = type;
        options.chromaticities = chromaticitiesOf(ColorConfig::shipped(), "ACEScg");
        options.camera = &scene.camera;
        options.attributes = {{"software", "vdb_ewa test"}, {"vdb_ewa/slab", "2"}};
        writeExr(frame, path, options);

        Imf::InputFile file(path.c_str());
        const Imf::Header& h = file.header();
        const Imf::PixelType colour = type == ExrPixelType::Half ? Imf::HALF : Imf::FLOAT;
        std::vector<std::string> names;
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            names.push_back(it.name());
            EXPECT_EQ(it.channel().type, std::string(it.name()) == "Z" ? Imf::FLOAT : colour) << it.name();
        }
        EXPECT_EQ(names, (std::vector<std::string>{"A", "B", "G", "R", "Z", "emission.B", "emission.G", "emission.R",
                             "shadow.B", "shadow.G", "shadow.R", "transmittance.B", "transmittance.G", "transmittance.R"}));
        const double tolerance = type == ExrPixelType::Half ? 1e-3 : 0.0; // half: 11-bit mantissa
        auto expectPlane = [&](const std::string& name, const std::vector<float>& values, int stride, int offset) {
            const std::vector<float> read = readChannel(path, name);
            ASSERT_EQ(read.size() * std::size_t(stride), values.size()) << name;
            for (std::size_t i = 0; i < read.size(); ++i) {
                const float v = values[i * std::size_t(stride) + std::size_t(offset)];
                if (std::isinf(v)) EXPECT_EQ(read[i], v) << name;
                else EXPECT_NEAR(read[i], v, tolerance * std::max(1.0f, std::abs(v))) << name << " pixel " << i;
            }
        };
        for (int c = 0; c < 4; ++c) expectPlane(std::string(1, "RGBA"[c]), frame.beauty.rgba, 4, c);
        expectPlane("Z", frame.depth, 1, 0);
        for (int c = 0; c < 3; ++c) {
            const std::string ch(1, "RGB"[c]);
            expectPlane("transmittance." + ch, frame.transmittance, 3, c);
            expectPlane("shadow." + ch, frame.shadow, 3, c);
            expectPlane("emission." + ch, frame.emission, 3, c);
        }
        ASSERT_TRUE(Imf::hasChromaticities(h));
        EXPECT_FLOAT_EQ(Imf::chromaticities(h).red.x, 0.713f);
        EXPECT_FLOAT_EQ(Imf::chromaticities(h).white.y, 0.33767f);
        EXPECT_EQ(h.typedAttribute<Imf::StringAttribute>("software").value(), "vdb_ewa test");
        EXPECT_EQ(h.typedAttribute<Imf::StringAttribute>("vdb_ewa/slab").value(), "2");
        EXPECT_EQ(h.compression(), Imf::ZIP_COMPRESSION);
        EXPECT_NEAR(h.screenWindowWidth(), scene.camera.width() / scene.camera.focalPixels(), 1e-6);
    }
}

TEST(ExrOutput, HalfClampsToItsRangeInsteadOfInfinity)
{
    Frame frame;
    frame.beauty = Image(2, 1);
    frame.beauty.rgba = {1e6f, -1e6f, 0.5f, 1.0f, 70000.0f, 1.0f, 2.0f, 1.0f};
    TempDir dir;
    writeExr(frame, dir.file("h.exr"), ExrOptions{});
    const std::vector<float> r = readChannel(dir.file("h.exr"), "R"), g = readChannel(dir.file("h.exr"), "G");
    EXPECT_EQ(r[0], 65504.0f);
    EXPECT_EQ(g[0], -65504.0f);
    EXPECT_EQ(r[1], 65504.0f);
    EXPECT_EQ(g[1], 1.0f);
}

TEST(ExrOutput, CameraMatricesProjectLikeTheCamera)
{
    for (const Projection projection : {Projection::Perspective, Projection::Orthographic}) {
        CameraSettings c;
        c.projection = projection;
        c.width = 64;
        c.height = 48;
        c.translate = Vec3d(1.0, 2.0, 5.0);
        c.lookAt = Vec3d(0.2, -0.1, 0.3);
        c.frame = 3.0;
        const Camera camera(c, Vec3d(0.0));
        TempDir dir;
        Frame frame;
        frame.beauty = Image(64, 48);
        ExrOptions options;
        options.camera = &camera;
        writeExr(frame, dir.file("m.exr"), options);
        Imf::InputFile file(dir.file("m.exr").c_str());
        ASSERT_TRUE(Imf::hasWorldToCamera(file.header()) && Imf::hasWorldToNDC(file.header()));
        const Imath::M44f toCamera = Imf::worldToCamera(file.header()), toNdc = Imf::worldToNDC(file.header());
        for (const Vec3d& p : {Vec3d(0.2, -0.1, 0.3), Vec3d(0.7, 0.4, -0.5), Vec3d(-0.6, 0.3, 0.2)}) {
            const Vec3d t = camera.cameraFromWorldPoint(p); // x right, y down, z forward
            Imath::V3f q;
            toCamera.multVecMatrix(Imath::V3f(float(p.x), float(p.y), float(p.z)), q);
            EXPECT_NEAR(q.x, t.x, 1e-5);
            EXPECT_NEAR(q.y, -t.y, 1e-5) << "OpenEXR camera space has y up";
            EXPECT_NEAR(q.z, t.z, 1e-5) << "and z forward";
            const Vec2d raster = camera.rasterFromCamera(t);
            toNdc.multVecMatrix(Imath::V3f(float(p.x), float(p.y), float(p.z)), q);
            EXPECT_NEAR(q.x, raster.x / 64.0, 1e-5);
            EXPECT_NEAR(q.y, raster.y / 48.0, 1e-5);
        }
    }
}

TEST(ExrOutput, EveryCompressionReadsBack)
{
    const CloudView scene;
    const Frame frame = renderAll(scene);
    TempDir dir;
    for (const ExrCompression c : {ExrCompression::None, ExrCompression::Rle, ExrCompression::Zip, ExrCompression::Zips,
             ExrCompression::Piz, ExrCompression::Dwaa, ExrCompression::Dwab}) {
        const std::string path = dir.file("c" + std::to_string(int(c)) + ".exr");
        ExrOptions options;
        options.colorType = ExrPixelType::Float;
        options.compression = c;
        writeExr(frame, path, options);
        const bool lossy = c == ExrCompression::Dwaa || c == ExrCompression::Dwab;
        const std::vector<float> r = readChannel(path, "R"), a = readChannel(path, "A"), z = readChannel(path, "Z");
        for (std::size_t i = 0; i < a.size(); ++i) {
            // DWA is lossy on R, G, B only; alpha and Z stay exact.
            EXPECT_EQ(a[i], frame.beauty.rgba[4 * i + 3]) << int(c);
            EXPECT_EQ(z[i], frame.depth[i]) << int(c);
            EXPECT_NEAR(r[i], frame.beauty.rgba[4 * i], lossy ? 0.02 : 0.0) << int(c);
        }
    }
}

TEST(ExrOutput, DeepFileIsTidyAndFlattensToTheBeauty)
{
    const CloudView scene;
    const Frame flat = renderAll(scene);
    const Frame deep = renderAll(scene, true);
    TempDir dir;
    for (const ExrPixelType type : {ExrPixelType::Half, ExrPixelType::Float}) {
        const std::string path = dir.file("deep.exr");
        ExrOptions options;
        options.colorType = type;
        options.compression = ExrCompression::Zips;
        writeDeepExr(deep.deep, path, options);

        Imf::DeepScanLineInputFile file(path.c_str());
        ASSERT_TRUE(Imf::hasDeepImageState(file.header()));
        EXPECT_EQ(Imf::deepImageState(file.header()), Imf::DIS_TIDY);
        const int w = 64, h = 48;
        std::vector<unsigned> counts(std::size_t(w) * h);
        Imf::DeepFrameBuffer fb;
        fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()), sizeof(unsigned), sizeof(unsigned) * w));
        const char* names[6] = {"R", "G", "B", "A", "Z", "ZBack"};
        std::vector<std::vector<float*>> pointers(6, std::vector<float*>(counts.size()));
        for (int c = 0; c < 6; ++c) {
            fb.insert(names[c], Imf::DeepSlice(Imf::FLOAT, reinterpret_cast<char*>(pointers[std::size_t(c)].data()),
                                    sizeof(float*), sizeof(float*) * w, sizeof(float)));
        }
        file.setFrameBuffer(fb);
        file.readPixelSampleCounts(0, h - 1);
        std::vector<std::vector<float>> storage(6);
        const std::size_t total = std::accumulate(counts.begin(), counts.end(), std::size_t(0));
        ASSERT_EQ(total, deep.deep.samples.size());
        for (int c = 0; c < 6; ++c) {
            storage[std::size_t(c)].resize(total);
            std::size_t next = 0;
            for (std::size_t i = 0; i < counts.size(); ++i) {
                pointers[std::size_t(c)][i] = storage[std::size_t(c)].data() + next;
                next += counts[i];
            }
        }
        file.readPixels(0, h - 1);
        double worst = 0.0;
        std::size_t next = 0;
        for (std::size_t i = 0; i < counts.size(); ++i) {
            double out[4] = {0, 0, 0, 0};
            for (unsigned k = 0; k < counts[i]; ++k, ++next) {
                EXPECT_LT(storage[4][next], storage[5][next]);
                const double t = 1.0 - out[3];
                for (int c = 0; c < 4; ++c) out[c] += t * storage[std::size_t(c)][next];
            }
            for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(out[c] - flat.beauty.rgba[4 * i + std::size_t(c)]));
        }
        EXPECT_LT(worst, 1e-3) << (type == ExrPixelType::Half ? "half" : "float");
    }
    ExrOptions zip;
    zip.compression = ExrCompression::Zip;
    EXPECT_THROW(writeDeepExr(deep.deep, dir.file("zip.exr"), zip), ValueError) << "OpenEXR 3.1 rejects ZIP for deep data";
    EXPECT_FALSE(std::filesystem::exists(dir.file("zip.exr")));
}

TEST(ExrOutput, FailedWritesLeaveTheExistingFileByteIdentical)
{
    TempDir dir;
    const std::string path = dir.file("shot.exr");
    const CloudView scene;
    const Frame frame = renderAll(scene);
    writeExr(frame, path, ExrOptions{});
    const std::string before = slurp(path);
    const std::vector<std::string> files = folderContents(path);

    // A write that dies half-way (a full disk, a crash in the encoder).
    EXPECT_THROW(detail::writeAtomically(path, "EXR", [](const std::string& tmp) {
        std::ofstream(tmp) << "half a file";
        throw std::runtime_error("No space left on device");
    }), IoError);
    // Invalid deep compression, and a deep write over the same path.
    ExrOptions piz;
    piz.compression = ExrCompression::Piz;
    EXPECT_THROW(writeDeepExr(renderAll(scene, true).deep, path, piz), ValueError);
    EXPECT_EQ(slurp(path), before);
    EXPECT_EQ(folderContents(path), files) << "no temporary file left behind";
    // Paths that cannot be written are refused before anything is written.
    EXPECT_THROW(checkOutputWritable(dir.file("missing/shot.exr")), IoError);
    EXPECT_THROW(writeExr(frame, dir.file("missing/shot.exr"), ExrOptions{}), IoError);
    std::filesystem::create_directory(dir.file("folder.exr"));
    EXPECT_THROW(writeExr(frame, dir.file("folder.exr"), ExrOptions{}), IoError);
}

// removeTemporaryOutputs (a host's hard stop, e.g. the CLI's signal watchdog) removes the
// temporary files of the writes in progress, and only those: a finished output and a file
// being replaced stay byte-identical.
TEST(ExrOutput, RemoveTemporaryOutputsRemovesOnlyTheWritesInProgress)
{
    TempDir dir;
    const std::string path = dir.file("shot.exr"), other = dir.file("other.exr");
    const CloudView scene;
    const Frame frame = renderAll(scene);
    writeExr(frame, path, ExrOptions{});
    writeExr(frame, other, ExrOptions{});
    const std::string before = slurp(path), otherBefore = slurp(other);
    removeTemporaryOutputs(); // nothing in progress: nothing removed
    EXPECT_EQ(slurp(path), before);
    std::string temporary;
    EXPECT_THROW(detail::writeAtomically(path, "EXR", [&](const std::string& tmp) {
        temporary = tmp;
        std::ofstream(tmp) << "half a file";
        ASSERT_TRUE(std::filesystem::exists(tmp));
        removeTemporaryOutputs(); // the stop arrives mid-write
        EXPECT_FALSE(std::filesystem::exists(tmp));
    }), IoError) << "the rename of the removed file fails";
    EXPECT_FALSE(temporary.empty());
    EXPECT_EQ(slurp(path), before);
    EXPECT_EQ(slurp(other), otherBefore);
    EXPECT_EQ(folderContents(path), (std::vector<std::string>{"other.exr", "shot.exr"}));
}

namespace {

/// Each chunk's packed and unpacked sizes, as OpenEXRCore reads them from a scanline file.
std::vector<std::pair<std::uint64_t, std::uint64_t>> chunkSizes(const std::string& path)
{
    exr_context_t ctx = nullptr;
    EXPECT_EQ(exr_start_read(&ctx, path.c_str(), nullptr), EXR_ERR_SUCCESS);
    int chunks = 0, lines = 0;
    EXPECT_EQ(exr_get_chunk_count(ctx, 0, &chunks), EXR_ERR_SUCCESS);
    EXPECT_EQ(exr_get_scanlines_per_chunk(ctx, 0, &lines), EXR_ERR_SUCCESS);
    std::vector<std::pair<std::uint64_t, std::uint64_t>> sizes;
    for (int c = 0; c < chunks; ++c) {
        exr_chunk_info_t info;
        EXPECT_EQ(exr_read_scanline_chunk_info(ctx, 0, c * lines, &info), EXR_ERR_SUCCESS);
        sizes.emplace_back(info.packed_size, info.unpacked_size);
    }
    exr_finish(&ctx);
    return sizes;
}

} // namespace

// The zip writer (libdeflate through OpenEXRCore, lib/output/exr_zip_writer.h) against OpenEXR's
// reader: every value back bit for bit, chunks of 16 lines (zip) and 1 (zips) with a last one cut
// short, a chunk of noise that deflate cannot shrink stored as it is (the format's rule), smooth
// chunks shrunk, and the same bytes whatever the threads.
TEST(ExrOutput, ZipFilesReadBackBitForBitWhateverTheirChunks)
{
    const int w = 13, h = 37; // 16 + 16 + 5 lines
    Frame frame;
    frame.beauty = Image(w, h);
    frame.depth.resize(std::size_t(w) * h);
    std::uint32_t state = 12345u;
    auto noise = [&] { // every bit random: no deflate shrinks it
        state = state * 1664525u + 1013904223u;
        float f;
        const std::uint32_t bits = (state & 0x807fffffu) | 0x3f000000u; // finite, 0.5 to 1 in size
        std::memcpy(&f, &bits, sizeof f);
        return f;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * w + std::size_t(x);
            const bool noisy = y >= 16 && y < 32; // the second zip chunk
            for (int c = 0; c < 4; ++c) frame.beauty.rgba[4 * i + std::size_t(c)] = noisy ? noise() : 0.25f + 0.01f * float(c);
            frame.depth[i] = noisy ? noise() : 10.0f;
        }
    frame.beauty.rgba[0] = 1e6f; // clamped to half's range
    TempDir dir;
    for (const ExrCompression c : {ExrCompression::Zip, ExrCompression::Zips})
        for (const ExrPixelType type : {ExrPixelType::Half, ExrPixelType::Float}) {
            const std::string name = std::string(c == ExrCompression::Zip ? "zip" : "zips") + (type == ExrPixelType::Half ? "_half" : "_float");
            const std::string path = dir.file(name + ".exr");
            ExrOptions options;
            options.compression = c;
            options.colorType = type;
            writeExr(frame, path, options);
            for (int ch = 0; ch < 4; ++ch) {
                const std::vector<float> read = readChannel(path, std::string(1, "RGBA"[ch]));
                for (std::size_t i = 0; i < read.size(); ++i) {
                    const float v = frame.beauty.rgba[4 * i + std::size_t(ch)];
                    const float expected = type == ExrPixelType::Half ? float(detail::toHalf(v)) : v;
                    ASSERT_EQ(read[i], expected) << name << " channel " << ch << " pixel " << i;
                }
            }
            EXPECT_EQ(readChannel(path, "Z"), frame.depth) << name;

            const auto sizes = chunkSizes(path);
            ASSERT_EQ(sizes.size(), c == ExrCompression::Zip ? 3u : 37u) << name;
            const std::size_t noisyChunk = c == ExrCompression::Zip ? 1 : 20, smoothChunk = c == ExrCompression::Zip ? 0 : 5;
            if (type == ExrPixelType::Float) { // as half, the noise's fixed exponent bits shrink a little
                EXPECT_EQ(sizes[noisyChunk].first, sizes[noisyChunk].second) << name << ": noise is stored as it is";
            }
            EXPECT_LT(sizes[smoothChunk].first * 4, sizes[smoothChunk].second) << name << ": smooth lines shrink";
        }

    // The same bytes on one thread and on several.
    const int threads = Imf::globalThreadCount();
    ExrOptions options;
    Imf::setGlobalThreadCount(0);
    writeExr(frame, dir.file("one.exr"), options);
    Imf::setGlobalThreadCount(4);
    writeExr(frame, dir.file("four.exr"), options);
    Imf::setGlobalThreadCount(threads);
    EXPECT_EQ(slurp(dir.file("one.exr")), slurp(dir.file("four.exr")));
}

// EXR's zip of a chunk, undone by hand with zlib (not libdeflate, which made it): inflate, then
// undo the difference and the even/odd split (the OpenEXR file format's definition of ZIP).
TEST(ExrOutput, ZipChunkIsTheFormatsPredictorAndSplitThenZlib)
{
    std::vector<unsigned char> raw(1001);
    for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = static_cast<unsigned char>((i / 7) * 3 + (i % 2) * 100);
    std::vector<unsigned char> packed;
    detail::zipChunk(raw, 1, packed);
    ASSERT_LT(packed.size(), raw.size() / 4);
    std::vector<unsigned char> inflated(raw.size());
    uLongf size = uLongf(inflated.size());
    ASSERT_EQ(uncompress(inflated.data(), &size, packed.data(), uLong(packed.size())), Z_OK);
    ASSERT_EQ(size, raw.size());
    for (std::size_t i = 1; i < inflated.size(); ++i) inflated[i] = static_cast<unsigned char>(inflated[i - 1] + inflated[i] - 128);
    std::vector<unsigned char> unsplit(raw.size());
    const std::size_t half = (raw.size() + 1) / 2;
    for (std::size_t i = 0; i < raw.size(); ++i) unsplit[i] = i % 2 ? inflated[half + i / 2] : inflated[i / 2];
    EXPECT_EQ(unsplit, raw);
}
