/// @file huge_page_allocator.h
/// @brief Storage for the pipeline's large arrays (kernels, splats, slab shares, tile bins, the
///        light map) and the frame's: blocks of kHugeBlockBytes or more are mapped 2 MiB-aligned,
///        so that the kernel can back them with transparent huge pages, and are advised
///        MADV_HUGEPAGE where that cannot stall (huge_page_allocator.cpp, adviseHugePages):
///        where the kernel's defrag policy is "defer", or while free 2 MiB blocks abound. A
///        first touch in 4 KiB pages costs a page fault each, 18 us on this machine's virtual
///        machine (docs/performance.md#fixed-costs). Smaller blocks use operator new; where
///        MADV_HUGEPAGE is not defined, large blocks are still mapped, without the advice.
#pragma once

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// Blocks at least this large are mapped as huge pages.
constexpr std::size_t kHugeBlockBytes = std::size_t(4) << 20;

/// @a bytes (>= kHugeBlockBytes) of memory, 2 MiB-aligned (advised as huge pages where that
/// cannot stall): a fresh mapping; throws std::bad_alloc. (Blocks are not kept for reuse: a
/// cache of freed blocks held 220 MB resident on a 10M-voxel cloud's streamed frame and gained
/// no time on any shared asset, docs/performance.md#memory-bounded-by-the-window.)
void* mapHugeBlock(std::size_t bytes);
/// Unmap a block from mapHugeBlock of the same size.
void unmapHugeBlock(void* block, std::size_t bytes) noexcept;
/// Advise the whole 2 MiB pages inside [@a data, @a data + @a bytes) as huge pages where that
/// cannot stall (as mapHugeBlock's blocks). For memory allocated but not yet touched.
void adviseHugePagesFor(const void* data, std::size_t bytes) noexcept;

/// @a v resized to @a n values of @a value, its storage advised as huge pages before the first
/// touch (for arrays whose type is fixed, such as the frame's std::vector<float> planes).
template <typename T, typename A>
void assignAdvised(std::vector<T, A>& v, std::size_t n, const T& value)
{
    std::vector<T, A>().swap(v);
    v.reserve(n);
    adviseHugePagesFor(v.data(), n * sizeof(T));
    v.assign(n, value);
}

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

/// @a n values of a trivial type, uninitialised, from HugePageAllocator: memory is touched
/// only where written (the light map's samples, marched on demand in any order, each tile's
/// into a range of its own).
template <typename T>
class UntouchedArray
{
public:
    UntouchedArray() = default;
    explicit UntouchedArray(std::size_t n) : mData(n > 0 ? HugePageAllocator<T>().allocate(n) : nullptr), mSize(n) {}
    ~UntouchedArray()
    {
        if (mData) HugePageAllocator<T>().deallocate(mData, mSize);
    }
    UntouchedArray(UntouchedArray&& other) noexcept : mData(std::exchange(other.mData, nullptr)), mSize(std::exchange(other.mSize, 0)) {}
    UntouchedArray& operator=(UntouchedArray&& other) noexcept
    {
        std::swap(mData, other.mData);
        std::swap(mSize, other.mSize);
        return *this;
    }
    T* data() const { return mData; }
    std::size_t size() const { return mSize; }

private:
    T* mData = nullptr;
    std::size_t mSize = 0;
};

} // namespace detail
} // namespace vdb_ewa
