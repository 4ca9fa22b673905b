/// @file exr_zip_writer.cpp
/// @brief Zip and zips EXRs through OpenEXRCore, deflated by libdeflate (exr_zip_writer.h).
#include "output/exr_zip_writer.h"

#include <OpenEXR/ImfThreading.h>
#include <OpenEXR/openexr.h>
#include <libdeflate.h>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>

namespace vdb_ewa {
namespace detail {
namespace {

/// OpenEXRCore's last message on this thread (its error callback; the default one prints).
thread_local std::string tCoreMessage;

void keepCoreMessage(exr_const_context_t, exr_result_t, const char* message) { tCoreMessage = message ? message : ""; }

/// Not a vdb_ewa error: writeAtomically names the destination, not the temporary file.
void check(exr_result_t result, const char* step)
{
    if (result == EXR_ERR_SUCCESS) return;
    const std::string why = tCoreMessage.empty() ? exr_get_default_error_message(result) : tCoreMessage;
    tCoreMessage.clear();
    throw std::runtime_error(std::string(step) + ": " + why);
}

struct CompressorDeleter
{
    void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};
using Compressor = std::unique_ptr<libdeflate_compressor, CompressorDeleter>;

Compressor makeCompressor(int level)
{
    Compressor c(libdeflate_alloc_compressor(std::clamp(level, 1, 12)));
    if (!c) throw std::bad_alloc();
    return c;
}

/// EXR's zip pre-pass (ImfZip.cpp): even bytes first, odd bytes after, then each byte minus the
/// one before plus 128 (mod 256), which turns smooth pixels' slowly changing bytes into runs.
void reorderAndDifference(const unsigned char* __restrict raw, std::size_t size, unsigned char* __restrict out,
    std::vector<unsigned char>& scratch)
{
    if (size == 0) return;
    scratch.resize(size);
    unsigned char* __restrict split = scratch.data();
    const std::size_t pairs = size / 2, odd = (size + 1) / 2;
    for (std::size_t j = 0; j < pairs; ++j) { // (indexed, so that the compiler vectorises both loops)
        split[j] = raw[2 * j];
        split[odd + j] = raw[2 * j + 1];
    }
    if (size % 2) split[pairs] = raw[size - 1];
    out[0] = split[0];
    for (std::size_t i = 1; i < size; ++i) out[i] = static_cast<unsigned char>(split[i] - split[i - 1] + 128);
}

/// Deflate @a raw (size bytes) into @a out: the zlib stream when smaller than @a raw, else @a raw.
void deflateChunk(libdeflate_compressor* compressor, const unsigned char* raw, std::size_t size,
    std::vector<unsigned char>& prepared, std::vector<unsigned char>& scratch, std::vector<unsigned char>& out)
{
    prepared.resize(size);
    reorderAndDifference(raw, size, prepared.data(), scratch);
    out.resize(size);
    // A stream that does not fit in size - 1 bytes returns 0: the chunk is stored as it is.
    const std::size_t packed = size > 1 ? libdeflate_zlib_compress(compressor, prepared.data(), size, out.data(), size - 1) : 0;
    if (packed == 0) std::memcpy(out.data(), raw, size);
    else out.resize(packed);
}

/// A chunk's lines as EXR stores them: line by line, each channel's values in name order.
void packChunk(const std::vector<ExrPlane>& planes, int width, int firstLine, int lines, std::vector<unsigned char>& out)
{
    std::size_t lineBytes = 0;
    for (const ExrPlane& p : planes) lineBytes += std::size_t(width) * (p.half ? sizeof(half) : sizeof(float));
    out.resize(lineBytes * std::size_t(lines));
    unsigned char* o = out.data();
    for (int y = firstLine; y < firstLine + lines; ++y) {
        for (const ExrPlane& p : planes) {
            const float* v = p.values + std::size_t(y) * std::size_t(width) * p.stride;
            if (p.half) {
                for (int x = 0; x < width; ++x, o += sizeof(half)) {
                    const unsigned short bits = toHalf(v[std::size_t(x) * p.stride]).bits();
                    std::memcpy(o, &bits, sizeof bits); // little-endian, as EXR and x86
                }
            } else {
                for (int x = 0; x < width; ++x, o += sizeof(float)) std::memcpy(o, &v[std::size_t(x) * p.stride], sizeof(float));
            }
        }
    }
}

/// The write context, finished (or abandoned) on every path out.
struct Context
{
    exr_context_t handle = nullptr;
    ~Context()
    {
        if (handle) exr_finish(&handle);
    }
};

void writeHeader(exr_context_t ctx, const ExrHeader& header, const std::vector<ExrPlane>& planes)
{
    // Names over 31 characters (vdb_ewa's statistics) need the long-name flag, set first.
    bool longNames = false;
    for (const ExrPlane& p : planes) longNames |= p.name.size() > 31;
    for (const auto& [key, value] : header.strings) longNames |= key.size() > 31;
    if (longNames) check(exr_set_longname_support(ctx, 1), "long names");
    int part = 0;
    check(exr_add_part(ctx, nullptr, EXR_STORAGE_SCANLINE, &part), "part");
    const exr_compression_t compression = header.compression == ExrCompression::Zips ? EXR_COMPRESSION_ZIPS : EXR_COMPRESSION_ZIP;
    check(exr_initialize_required_attr_simple(ctx, part, header.width, header.height, compression), "header");
    for (const ExrPlane& p : planes) {
        check(exr_add_channel(ctx, part, p.name.c_str(), p.half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
            "channel");
    }
    if (header.chromaticities) {
        const Chromaticities& c = *header.chromaticities;
        const exr_attr_chromaticities_t v = {float(c.red.x), float(c.red.y), float(c.green.x), float(c.green.y),
            float(c.blue.x), float(c.blue.y), float(c.white.x), float(c.white.y)};
        check(exr_attr_set_chromaticities(ctx, part, "chromaticities", &v), "chromaticities");
    }
    if (header.worldToCamera && header.worldToNdc) {
        exr_attr_m44f_t m;
        std::copy(header.worldToCamera->begin(), header.worldToCamera->end(), m.m);
        check(exr_attr_set_m44f(ctx, part, "worldToCamera", &m), "worldToCamera");
        std::copy(header.worldToNdc->begin(), header.worldToNdc->end(), m.m);
        check(exr_attr_set_m44f(ctx, part, "worldToNDC", &m), "worldToNDC");
    }
    check(exr_set_screen_window_width(ctx, part, header.screenWindowWidth), "screenWindowWidth");
    for (const auto& [key, value] : header.strings) check(exr_attr_set_string(ctx, part, key.c_str(), value.c_str()), key.c_str());
    check(exr_write_header(ctx), "header");
}

} // namespace

void zipChunk(const std::vector<unsigned char>& raw, int level, std::vector<unsigned char>& out)
{
    const Compressor compressor = makeCompressor(level);
    std::vector<unsigned char> prepared, scratch;
    deflateChunk(compressor.get(), raw.data(), raw.size(), prepared, scratch, out);
}

void writeZipExr(const std::string& path, const ExrHeader& header, std::vector<ExrPlane> planes, int level)
{
    // EXR stores a line's channels in name order (strcmp's, as OpenEXRCore's channel list).
    std::sort(planes.begin(), planes.end(), [](const ExrPlane& a, const ExrPlane& b) { return a.name < b.name; });
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = keepCoreMessage;
    Context ctx;
    tCoreMessage.clear();
    check(exr_start_write(&ctx.handle, path.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), "open");
    writeHeader(ctx.handle, header, planes);

    const int linesPerChunk = header.compression == ExrCompression::Zips ? 1 : 16;
    const int chunks = (header.height + linesPerChunk - 1) / linesPerChunk;
    const int threads = std::max(1, Imf::globalThreadCount());
    // A chunk in flight holds its buffers and compressor in slot (index % slots): at most `slots`
    // chunks are, and the in-order stages keep them consecutive, so the buffers are reused, not
    // re-faulted.
    const std::size_t slots = std::size_t(2 * threads);
    struct Slot
    {
        Compressor compressor;
        int firstLine = 0;
        std::vector<unsigned char> raw, prepared, scratch, packed;
    };
    std::vector<Slot> slot(slots);
    for (Slot& s : slot) s.compressor = makeCompressor(level);
    int next = 0;
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_pipeline(slots,
            tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                [&](tbb::flow_control& fc) {
                    if (next == chunks) fc.stop();
                    return next < chunks ? next++ : 0;
                }) &
                tbb::make_filter<int, int>(tbb::filter_mode::parallel,
                    [&](int chunk) {
                        Slot& s = slot[std::size_t(chunk) % slots];
                        s.firstLine = chunk * linesPerChunk;
                        packChunk(planes, header.width, s.firstLine, std::min(linesPerChunk, header.height - s.firstLine), s.raw);
                        deflateChunk(s.compressor.get(), s.raw.data(), s.raw.size(), s.prepared, s.scratch, s.packed);
                        return chunk;
                    }) &
                tbb::make_filter<int, void>(tbb::filter_mode::serial_in_order, [&](int chunk) {
                    const Slot& s = slot[std::size_t(chunk) % slots];
                    check(exr_write_scanline_chunk(ctx.handle, 0, s.firstLine, s.packed.data(), s.packed.size()), "chunk");
                }));
    });
    const exr_result_t finished = exr_finish(&ctx.handle); // the offset table
    ctx.handle = nullptr;
    check(finished, "close");
}

} // namespace detail
} // namespace vdb_ewa
