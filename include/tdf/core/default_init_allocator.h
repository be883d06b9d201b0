#pragma once
/// An allocator whose containers leave new trivial elements uninitialised: `resize(n)` and
/// `vector(n)` allocate without writing (std::allocator value-initialises, i.e. zero-fills, on
/// one thread). For buffers that are written in full, or filled in parallel, right after.
///
/// Blocks of kAlignedFrom bytes or more start on a 64-byte boundary (a cache line): the renderer
/// writes its frame's images with streaming stores a tile row at a time (render/stream_lanes.h),
/// and a row that starts mid-line leaves two half-written lines at every tile's edge, each sent to
/// memory twice. The same 27 MB of streaming stores took 2.3-2.4 ms from a base 16 bytes past a
/// line and 1.1-1.2 ms from a line (2026-12-07). The block is over-allocated by a line and the
/// address handed out is rounded up, the heap's own pointer kept just before it: aligned
/// operator new (glibc's memalign) split the heap's blocks instead and raised the main job's peak
/// from 584 to 667 MB.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace tdf {

template <typename T>
class DefaultInitAllocator : public std::allocator<T> {
public:
    using value_type = T;
    template <typename U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    static constexpr std::size_t kAlignment = 64;
    static constexpr std::size_t kAlignedFrom = std::size_t(64) << 10;
    static_assert(__STDCPP_DEFAULT_NEW_ALIGNMENT__ >= sizeof(void*), "room for the block's pointer");

    DefaultInitAllocator() noexcept = default;
    template <typename U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

    T* allocate(std::size_t n) {
        if (n > (std::size_t(-1) - kAlignment) / sizeof(T)) throw std::bad_array_new_length();
        const std::size_t bytes = n * sizeof(T);
        if (bytes < kAlignedFrom) return static_cast<T*>(::operator new(bytes));
        void* block = ::operator new(bytes + kAlignment);
        // The next line boundary lies at least operator new's alignment past the block's start:
        // room for the block's pointer just before it.
        const std::uintptr_t data =
            (reinterpret_cast<std::uintptr_t>(block) + kAlignment) & ~(kAlignment - 1);
        reinterpret_cast<void**>(data)[-1] = block;
        return reinterpret_cast<T*>(data);
    }
    void deallocate(T* p, std::size_t n) noexcept {
        if (n * sizeof(T) < kAlignedFrom)
            ::operator delete(p);
        else
            ::operator delete(reinterpret_cast<void**>(p)[-1]);
    }

    /// Default-initialisation: nothing is written for trivial types.
    template <typename U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

template <typename T, typename U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
    return true;
}
template <typename T, typename U>
bool operator!=(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept {
    return false;
}

}  // namespace tdf
