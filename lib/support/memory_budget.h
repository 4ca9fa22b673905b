/// @file memory_budget.h
/// @brief The memory a frame may use (RenderSettings::maxMemory, --max-memory), checked against
///        the counts each stage knows before it allocates (docs/numerics.md#memory-budget).
#pragma once

#include <cstdint>
#include <string>

namespace vdb_ewa {
namespace detail {

/// What one kernel costs through the pipeline (the kernel, its colour, splat, depth extent, slab
/// shares and their moments, pass sources, sweep entry and sort key): about 200 bytes measured
/// at 1080p (smoke: 263 MB peak for 1M kernels and a 2M-pixel frame), rounded up.
inline constexpr double kBytesPerKernel = 256.0;
/// What one pixel of a frame costs (beauty, depth, transmittance and pass planes, the EXR's
/// converted copy), rounded up.
inline constexpr double kBytesPerPixel = 96.0;

class MemoryBudget
{
public:
    /// @a maxMemory bytes (0: three quarters of the physical memory); @a subject names what is
    /// rendered in errors ("FILE: grid 'NAME'").
    MemoryBudget(double maxMemory, std::string subject);

    double bytes() const { return mBytes; }

    /// Throws BudgetError "SUBJECT: COUNT WHAT need SIZE, over the memory budget of SIZE
    /// (--max-memory)" when @a count items of @a bytesEach exceed the budget.
    void check(double count, const char* what, double bytesEach) const;

    /// The most items of @a bytesEach that fit in @a share of the budget.
    double itemsWithin(double share, double bytesEach) const { return share * mBytes / bytesEach; }

private:
    double mBytes;
    std::string mSubject;
};

/// Three quarters of the machine's physical memory, in bytes.
double defaultMemoryBudget();

/// @a bytes as "1.5 GB", "640 MB" (powers of 1024).
std::string formatBytes(double bytes);

} // namespace detail
} // namespace vdb_ewa
