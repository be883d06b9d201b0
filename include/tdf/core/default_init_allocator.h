#pragma once
/// An allocator whose containers leave new trivial elements uninitialised: `resize(n)` and
/// `vector(n)` allocate without writing (std::allocator value-initialises, i.e. zero-fills, on
/// one thread). For buffers that are written in full, or filled in parallel, right after.
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
    DefaultInitAllocator() noexcept = default;
    template <typename U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}

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
