/// @file memory_budget.cpp
#include "support/memory_budget.h"

#include <vdb_ewa/error.h>

#include <unistd.h>

#include <cstdio>
#include <utility>

namespace vdb_ewa {
namespace detail {

double defaultMemoryBudget()
{
    const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0) return 4.0 * 1024 * 1024 * 1024; // unknown: 4 GB
    return 0.75 * double(pages) * double(size);
}

std::string formatBytes(double bytes)
{
    const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB", "EB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 6) {
        bytes /= 1024.0;
        ++u;
    }
    char text[32];
    std::snprintf(text, sizeof text, u == 0 ? "%.0f %s" : "%.3g %s", bytes, units[u]);
    return text;
}

MemoryBudget::MemoryBudget(double maxMemory, std::string subject)
    : mBytes(maxMemory > 0.0 ? maxMemory : defaultMemoryBudget()), mSubject(std::move(subject))
{
}

void MemoryBudget::check(double count, const char* what, double bytesEach) const
{
    const double need = count * bytesEach;
    if (need <= mBytes) return;
    char number[32];
    std::snprintf(number, sizeof number, count < 1e15 ? "%.0f" : "%.3g", count);
    throw BudgetError(mSubject + ": " + number + " " + what + " need " + formatBytes(need) + ", over the memory budget of " +
                      formatBytes(mBytes) + " (--max-memory)");
}

} // namespace detail
} // namespace vdb_ewa
