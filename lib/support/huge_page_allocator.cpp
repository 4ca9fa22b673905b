/// @file huge_page_allocator.cpp
#include "support/huge_page_allocator.h"

#include <sys/mman.h>

#include <cstdint>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

namespace vdb_ewa {
namespace detail {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;


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

/// Blocks given back, kept for the next request of their size class (a streamed frame's windows
/// allocate alike arrays again and again; a fresh mapping costs a page fault every 4 KiB
/// touched, 5-10 us each on a virtual machine), up to kCachedBytes in all.
constexpr std::size_t kCachedBytes = std::size_t(1) << 30;

struct BlockCache
{
    std::mutex mutex;
    std::vector<std::pair<void*, std::size_t>> blocks; ///< block, its mapped size
    std::size_t bytes = 0;
};

BlockCache& blockCache()
{
    static BlockCache* cache = new BlockCache; // never destroyed: blocks may be freed at exit
    return *cache;
}

/// The mapped size of a block of @a bytes: a power of two (so that a block freed by one array
/// serves the next of about its size).
std::size_t sizeClass(std::size_t bytes)
{
    std::size_t size = kHugePage;
    while (size < bytes) size *= 2; // bytes <= SIZE_MAX / 4 (mapHugeBlock)
    return size;
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
    if (adviseHugePages()) madvise(block, size, MADV_HUGEPAGE); // a hint: otherwise the THP policy decides
#endif
    return block;
}

} // namespace

void* mapHugeBlock(std::size_t bytes)
{
    if (bytes > std::size_t(-1) / 4) throw std::bad_alloc();
    const std::size_t size = sizeClass(bytes);
    {
        BlockCache& cache = blockCache();
        const std::lock_guard<std::mutex> lock(cache.mutex);
        for (std::size_t i = 0; i < cache.blocks.size(); ++i) {
            if (cache.blocks[i].second != size) continue;
            void* block = cache.blocks[i].first;
            cache.blocks.erase(cache.blocks.begin() + std::ptrdiff_t(i));
            cache.bytes -= size;
            return block;
        }
    }
    return mapFresh(size);
}

void unmapHugeBlock(void* block, std::size_t bytes) noexcept
{
    if (!block) return;
    const std::size_t size = sizeClass(bytes);
    BlockCache& cache = blockCache();
    {
        const std::lock_guard<std::mutex> lock(cache.mutex);
        if (cache.bytes + size <= kCachedBytes) {
            try {
                cache.blocks.emplace_back(block, size);
                cache.bytes += size;
                return;
            } catch (...) {
            }
        }
    }
    munmap(block, size);
}

void releaseCachedBlocks() noexcept
{
    BlockCache& cache = blockCache();
    const std::lock_guard<std::mutex> lock(cache.mutex);
    for (const auto& [block, size] : cache.blocks) munmap(block, size);
    cache.blocks.clear();
    cache.bytes = 0;
}

} // namespace detail
} // namespace vdb_ewa
