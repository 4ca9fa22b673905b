/// @file error.h
/// @brief Exceptions thrown by the library. Messages are one line and name the file or
///        the setting at fault; the CLI prints them as they are.
#pragma once

#include <stdexcept>
#include <string>

#include "types.h"

namespace vdb_ewa {

/// Base of every exception the library throws.
class VDB_EWA_API Error : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/// A file could not be read or written (missing, unreadable, truncated, unwritable).
class VDB_EWA_API IoError : public Error
{
public:
    using Error::Error;
};

/// The input is readable but unusable (no such grid, unsupported grid type).
class VDB_EWA_API InputError : public Error
{
public:
    using Error::Error;
};

/// A setting is out of range or inconsistent (impossible camera, negative slab...).
class VDB_EWA_API ValueError : public Error
{
public:
    using Error::Error;
};

/// The render would need more memory than its budget allows (RenderSettings::maxMemory,
/// --max-memory): found from the counts known before anything is allocated.
class VDB_EWA_API BudgetError : public Error
{
public:
    using Error::Error;
};

} // namespace vdb_ewa
