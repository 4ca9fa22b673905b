/// @file huge_page_allocator.cpp
#include "support/huge_page_allocator.h"

#include <sys/mman.h>

#include <cstdint>
#include <fstream>
#include <string>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;

std::size_t roundUp(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

/// Whether MADV_HUGEPAGE can be given without stalling page faults: where the kernel's THP
/// defrag policy is "always", "madvise" (Debian's default) or "defer+madvise", a fault in an
/// advised region compacts memory synchronously when no huge page is free, and on a busy
/// machine that cost projection 0.2-0.45 s a frame (docs/performance.md#the-fast-end-1920x1080).
bool adviseHugePages()
{
    static const bool advise = [] {
        std::ifstream in("/sys/kernel/mm/transparent_hugepage/defrag");
        std::string policy;
        std::getline(in, policy);
        return policy.find("[defer]") != std::string::npos;
    }();
    return advise;
}

} // namespace

void* mapHugeBlock(std::size_t bytes)
{
    const std::size_t size = roundUp(bytes);
    if (size < bytes || size > std::size_t(-1) - kHugePage) throw std::bad_alloc();
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
    if (adviseHugePages()) madvise(block, size, MADV_HUGEPAGE); // a hint: otherwise the THP policy decides
#endif
    return block;
}

void unmapHugeBlock(void* block, std::size_t bytes) noexcept
{
    if (block) munmap(block, roundUp(bytes));
}

} // namespace detail
} // namespace vdb_ewa
