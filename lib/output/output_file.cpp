/// @file output_file.cpp
#include <vdb_ewa/output_file.h>

#include "output/atomic_write.h"

#include <vdb_ewa/error.h>

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace vdb_ewa {
namespace {

namespace fs = std::filesystem;

fs::path parentOf(const std::string& path)
{
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? fs::path(".") : parent;
}

/// The temporary files being written, for removeTemporaryOutputs (async-signal-safe: fixed
/// slots, atomics, no allocation). A slot is Free, Writing (its path being copied in) or Held.
/// A write with more slots in flight than kSlots, or a longer path, is not listed.
struct TemporarySlot
{
    enum State : int { Free, Writing, Held };
    std::atomic<int> state{Free};
    char path[4096];
};
constexpr int kSlots = 64;
TemporarySlot gTemporaries[kSlots];

/// Lists @a path in a free slot for its lifetime.
class ListedTemporary
{
public:
    explicit ListedTemporary(const std::string& path)
    {
        if (path.size() >= sizeof(TemporarySlot::path)) return;
        for (TemporarySlot& slot : gTemporaries) {
            int expected = TemporarySlot::Free;
            if (slot.state.compare_exchange_strong(expected, TemporarySlot::Writing)) {
                std::memcpy(slot.path, path.c_str(), path.size() + 1);
                slot.state.store(TemporarySlot::Held);
                mSlot = &slot;
                return;
            }
        }
    }
    ~ListedTemporary()
    {
        if (mSlot) mSlot->state.store(TemporarySlot::Free);
    }
    ListedTemporary(const ListedTemporary&) = delete;
    ListedTemporary& operator=(const ListedTemporary&) = delete;

private:
    TemporarySlot* mSlot = nullptr;
};

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

void removeTemporaryOutputs() noexcept
{
    for (TemporarySlot& slot : gTemporaries) {
        if (slot.state.load() == TemporarySlot::Held) ::unlink(slot.path);
    }
}

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
    const ListedTemporary listed(tmp);
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
