/// @file version.cpp
#include <vdb_ewa/vdb_ewa.h>

#include <string>

namespace vdb_ewa {

namespace detail {
/// The git commit of the sources ("657cd57", "657cd57-dirty" or "unknown"): version_git.cpp, which
/// lib/CMakeLists.txt writes at configure time.
extern const char* const kGitCommit;
} // namespace detail

const char* versionString()
{
    static const std::string version = std::string(VDB_EWA_VERSION_STRING) + " (git " + detail::kGitCommit + ")";
    return version.c_str();
}

} // namespace vdb_ewa
