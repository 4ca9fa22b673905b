/// @file image_codec.cpp
/// @brief Loads libvdb_ewa_images.so, the module that calls OpenImageIO (image_codec.h).
#include "output/image_codec.h"

#include <vdb_ewa/error.h>

#include <dlfcn.h>

#include <filesystem>
#include <vector>
#include <mutex>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr const char* kModule = "libvdb_ewa_images.so";
#define VDB_EWA_STRING(x) VDB_EWA_STRING_(x)
#define VDB_EWA_STRING_(x) #x
constexpr const char* kEntry = VDB_EWA_STRING(VDB_EWA_IMAGE_CODEC_ENTRY);

/// The folder of the binary this function is in (libvdb_ewa.so, or an executable linked with
/// the static library); empty if the loader cannot say.
std::filesystem::path ownFolder()
{
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&ownFolder), &info) == 0 || !info.dli_fname) return {};
    std::error_code ec;
    const std::filesystem::path self = std::filesystem::canonical(info.dli_fname, ec);
    return ec ? std::filesystem::path() : self.parent_path();
}

const ImageCodec* load(std::string& why)
{
    const std::filesystem::path folder = ownFolder();
    std::vector<std::string> beside; // the module's paths in the folders it is installed or built in
    if (!folder.empty()) {
        beside.push_back((folder / kModule).string());
        beside.push_back((folder.parent_path() / "lib" / kModule).string()); // the build tree's tests/
    }
    // Only there: not through the dynamic loader's search path, where another build's or
    // version's module could be found first.
    for (const std::string& candidate : beside) {
        std::error_code ec;
        if (!std::filesystem::exists(candidate, ec)) continue;
        void* handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* error = dlerror();
            why = error ? error : candidate + ": cannot be loaded";
            continue;
        }
        using Entry = const ImageCodec* (*)();
        const auto entry = reinterpret_cast<Entry>(dlsym(handle, kEntry));
        if (!entry) {
            why = candidate + " is from another version of vdb_ewa (no " + kEntry + ")";
            dlclose(handle);
            continue;
        }
        return entry(); // the handle stays open for the process's life
    }
    if (why.empty()) why = std::string(kModule) + " is not in " + (folder.empty() ? std::string("vdb_ewa's folder") : folder.string());
    return nullptr;
}

} // namespace

const ImageCodec& imageCodec()
{
    static std::once_flag once;
    static const ImageCodec* codec = nullptr;
    static std::string why;
    std::call_once(once, [] { codec = load(why); });
    if (!codec) throw Error("vdb_ewa's image module (OpenImageIO, for every format but EXR) cannot be loaded: " + why + "; reinstall vdb_ewa");
    return *codec;
}

} // namespace detail
} // namespace vdb_ewa
