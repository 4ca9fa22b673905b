/// @file huge_page_allocator.cpp
#include "support/huge_page_allocator.h"

#include <sys/mman.h>

#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;


/// The kernel's THP defrag policy, as the bracketed word of its sysfs file ("madvise" on Debian).
const std::string& defragPolicy()
{
    static const std::string policy = [] {
        std::ifstream in("/sys/kernel/mm/transparent_hugepage/defrag");
        std::string line;
        std::getline(in, line);
        const std::size_t open = line.find('['), close = line.find(']');
        return open != std::string::npos && close > open ? line.substr(open + 1, close - open - 1) : std::string();
    }();
    return policy;
}

/// Free 2 MiB blocks the buddy allocator holds now (/proc/buddyinfo: free blocks per order per
/// zone; order 9 is 2 MiB on x86-64), or 0 if unknown.
std::size_t freeHugePages()
{
    std::ifstream in("/proc/buddyinfo");
    std::size_t pages = 0;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream fields(line);
        std::string node, id, zone, word;
        fields >> node >> id >> word >> zone; // "Node 0, zone Normal"
        std::size_t count = 0;
        for (int order = 0; fields >> count; ++order) {
            if (order >= 9) pages += count << (order - 9);
        }
    }
    return pages;
}

/// Whether to advise MADV_HUGEPAGE for @a bytes about to be touched. Where the defrag policy is
/// "defer", a fault with no free huge page falls back to small pages: always. Where it is
/// "madvise" (Debian's default), "always" or "defer+madvise", such a fault compacts memory
/// synchronously, which stalled projection 0.2-0.45 s on a busy machine
/// (docs/performance.md#fixed-costs): advise only while the buddy allocator holds free 2 MiB
/// blocks for the request and 512 MiB more. A 40 MB array's first touch then costs 11 ms
/// instead of 180 ms on this machine's virtual machine (18 us a 4 KiB fault).
bool adviseHugePages(std::size_t bytes)
{
    const std::string& policy = defragPolicy();
    if (policy == "defer") return true;
    if (policy == "never" || policy.empty()) return false;
    return freeHugePages() >= bytes / kHugePage + 256;
}

/// The mapped size of a block of @a bytes: whole huge pages.
std::size_t mappedSize(std::size_t bytes)
{
    return (bytes + kHugePage - 1) / kHugePage * kHugePage;
}

void* mapFresh(std::size_t size)
{
    // Over-map by one huge page and trim, so the block starts on a 2 MiB boundary.
    void* raw = mmap(nullptr, size + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (raw == MAP_FAILED) throw std::bad_alloc();
    const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(raw);
    const std::uintptr_t aligned = (start + kHugePage - 1) / kHugePage * kHugePage;
    if (aligned > start) munmap(raw, aligned - start);
    const std::size_t tail = (start + size + kHugePage) - (aligned + size);
    if (tail > 0) munmap(reinterpret_cast<void*>(aligned + size), tail);
    void* block = reinterpret_cast<void*>(aligned);
#ifdef MADV_HUGEPAGE
    if (adviseHugePages(size)) madvise(block, size, MADV_HUGEPAGE); // a hint: otherwise the THP policy decides
#endif
    return block;
}

} // namespace

void* mapHugeBlock(std::size_t bytes)
{
    if (bytes > std::size_t(-1) / 4) throw std::bad_alloc();
    return mapFresh(mappedSize(bytes));
}

void unmapHugeBlock(void* block, std::size_t bytes) noexcept
{
    if (block) munmap(block, mappedSize(bytes));
}

void adviseHugePagesFor(const void* data, std::size_t bytes) noexcept
{
#ifdef MADV_HUGEPAGE
    // The 2 MiB pages that lie wholly inside [data, data + bytes): madvise takes page-aligned
    // ranges, and only whole huge pages can be backed by one.
    const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHugePage - 1) / kHugePage * kHugePage;
    const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) / kHugePage * kHugePage;
    if (end > begin && adviseHugePages(end - begin)) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
    (void)data;
    (void)bytes;
#endif
}

} // namespace detail
} // namespace vdb_ewa
