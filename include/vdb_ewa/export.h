/// @file export.h
/// @brief VDB_EWA_API marks the classes and functions libvdb_ewa.so exports. The library is
///        compiled with hidden visibility by default: everything else stays internal.
#pragma once

#if defined(VDB_EWA_BUILDING)
#define VDB_EWA_API __attribute__((visibility("default")))
#else
#define VDB_EWA_API
#endif
