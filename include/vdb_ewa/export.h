/// @file export.h
/// @brief VDB_EWA_API marks the classes and functions libvdb_ewa.so exports. The library is
///        compiled with hidden visibility by default: everything else stays internal.
#pragma once

/// VDB_EWA_LOCAL marks the private members of an exported class (and its internal nested types)
/// hidden again: members of a VDB_EWA_API class are exported unless they say otherwise.
#if defined(VDB_EWA_BUILDING)
#define VDB_EWA_API __attribute__((visibility("default")))
#define VDB_EWA_LOCAL __attribute__((visibility("hidden")))
#else
#define VDB_EWA_API
#define VDB_EWA_LOCAL
#endif
