/// @file version.cpp
#include <vdb_ewa/vdb_ewa.h>

namespace vdb_ewa {

const char* versionString() { return VDB_EWA_VERSION_STRING; }

} // namespace vdb_ewa
