/// @file exr_output.cpp
/// @brief OpenEXR I/O. Writes go to a temporary file in the destination folder, renamed
///        over the destination only once complete.
#include <vdb_ewa/exr_output.h>

#include <vdb_ewa/error.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfThreading.h>

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <thread>

namespace vdb_ewa {
namespace {

namespace fs = std::filesystem;

fs::path parentOf(const std::string& path)
{
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

std::string temporaryPathFor(const std::string& path)
{
    static std::atomic<unsigned> counter{0};
    const fs::path p(path);
    return (parentOf(path) / ("." + p.filename().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                              std::to_string(counter++)))
        .string();
}

} // namespace

void checkOutputWritable(const std::string& path)
{
    std::error_code ec;
    if (path.empty()) throw IoError("output path is empty");
    const fs::path parent = parentOf(path);
    if (!fs::is_directory(parent, ec)) throw IoError(path + ": folder '" + parent.string() + "' does not exist");
    if (::access(parent.c_str(), W_OK) != 0) throw IoError(path + ": folder '" + parent.string() + "' is not writable");
    if (fs::is_directory(path, ec)) throw IoError(path + ": is a directory");
    if (fs::exists(path, ec) && ::access(path.c_str(), W_OK) != 0) throw IoError(path + ": exists and is not writable");
}

void writeExr(const Image& image, const std::string& path,
    const std::vector<std::pair<std::string, std::string>>& attributes)
{
    checkOutputWritable(path);
    const std::string tmp = temporaryPathFor(path);
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const auto& [key, value] : attributes) header.insert(key, Imf::StringAttribute(value));
        const char* names[4] = {"R", "G", "B", "A"};
        Imf::FrameBuffer fb;
        const std::size_t xStride = 4 * sizeof(float), yStride = xStride * std::size_t(image.width);
        char* base = reinterpret_cast<char*>(const_cast<float*>(image.rgba.data()));
        for (int c = 0; c < 4; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            fb.insert(names[c], Imf::Slice(Imf::FLOAT, base + c * sizeof(float), xStride, yStride));
        }
        {
            Imf::OutputFile file(tmp.c_str(), header);
            file.setFrameBuffer(fb);
            file.writePixels(image.height);
        }
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) throw IoError(path + ": cannot rename the finished temporary file (" + ec.message() + ")");
    } catch (const Error&) {
        std::remove(tmp.c_str());
        throw;
    } catch (const std::exception& e) {
        std::remove(tmp.c_str());
        throw IoError(path + ": cannot write EXR (" + std::string(e.what()) + ")");
    }
}

void setExrThreadsProcessWide(int threads)
{
    Imf::setGlobalThreadCount(threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency())));
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
