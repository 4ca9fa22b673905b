/// @file output_file.cpp
#include <vdb_ewa/output_file.h>

#include "output/atomic_write.h"

#include <vdb_ewa/error.h>

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>

namespace vdb_ewa {
namespace {

namespace fs = std::filesystem;

fs::path parentOf(const std::string& path)
{
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

/// A hidden name next to @a path, unique per process and call.
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

namespace detail {

void writeAtomically(const std::string& path, const std::string& what,
    const std::function<void(const std::string& temporaryPath)>& write)
{
    checkOutputWritable(path);
    const std::string tmp = temporaryPathFor(path);
    try {
        write(tmp);
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) throw IoError(path + ": cannot rename the finished temporary file (" + ec.message() + ")");
    } catch (const Error&) {
        std::remove(tmp.c_str());
        throw;
    } catch (const std::exception& e) {
        std::remove(tmp.c_str());
        throw IoError(path + ": cannot write " + what + " (" + std::string(e.what()) + ")");
    }
}

} // namespace detail
} // namespace vdb_ewa
