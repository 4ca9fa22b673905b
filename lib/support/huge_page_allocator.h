/// @file huge_page_allocator.h
/// @brief Storage for the pipeline's large arrays (kernels, splats, slab shares, tile bins, the
///        light map): blocks of kHugeBlockBytes or more are mapped 2 MiB-aligned, so that the
///        kernel can back them with transparent huge pages, and are advised MADV_HUGEPAGE only
///        where the kernel's defrag policy lets an advised fault fall back instead of compacting
///        memory synchronously ("defer"). Where it does not (Debian's "madvise"), advising made
///        the first touch 50 faults instead of 25,000 a 100 MB array but stalled for compaction
///        on a busy machine: 1080p smoke 4.2x faster than vdb_render with the advice, 4.9x
///        without (docs/performance.md). Smaller blocks use operator new; where MADV_HUGEPAGE is
///        not defined, large blocks are still mapped, without the advice.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// Blocks at least this large are mapped as huge pages.
constexpr std::size_t kHugeBlockBytes = std::size_t(4) << 20;

/// @a bytes (>= kHugeBlockBytes) of memory, 2 MiB-aligned (advised as huge pages where that
/// cannot stall): a block given back earlier if one of its size class is kept, else a fresh
/// mapping; throws std::bad_alloc.
void* mapHugeBlock(std::size_t bytes);
/// Give back a block from mapHugeBlock of the same size: kept for reuse (up to 1 GiB in all),
/// else unmapped.
void unmapHugeBlock(void* block, std::size_t bytes) noexcept;
/// Unmap every block kept for reuse (the end of a render).
void releaseCachedBlocks() noexcept;

template <typename T>
struct HugePageAllocator
{
    using value_type = T;

    HugePageAllocator() = default;
    template <typename U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    T* allocate(std::size_t n)
    {
        if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
        const std::size_t bytes = n * sizeof(T);
        if (bytes >= kHugeBlockBytes) return static_cast<T*>(mapHugeBlock(bytes));
        return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T))));
    }
    void deallocate(T* p, std::size_t n) noexcept
    {
        const std::size_t bytes = n * sizeof(T);
        if (bytes >= kHugeBlockBytes) unmapHugeBlock(p, bytes);
        else ::operator delete(p, std::align_val_t(alignof(T))); // unsized: clang has no sized delete by default
    }
    template <typename U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
    template <typename U>
    bool operator!=(const HugePageAllocator<U>&) const noexcept { return false; }
};

/// A std::vector for the pipeline's large arrays (HugePageAllocator).
template <typename T>
using LargeArray = std::vector<T, HugePageAllocator<T>>;

} // namespace detail
} // namespace vdb_ewa
