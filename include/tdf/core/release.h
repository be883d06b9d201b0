#pragma once
/// Giving a container's memory back. `v = {}` and `v.clear()` keep a std::vector's capacity
/// (libstdc++ assigns the empty initializer list in place), so a buffer "released" that way stays
/// allocated; these swap it with an empty one, which frees it.
#include <vector>

namespace tdf {

/// Empties `v` and frees its storage.
template <typename T, typename Allocator>
void release(std::vector<T, Allocator>& v) {
    std::vector<T, Allocator>().swap(v);
}

/// release() for several vectors of one type.
template <typename T, typename Allocator, typename... More>
void release(std::vector<T, Allocator>& first, More&... more) {
    release(first);
    (release(more), ...);
}

}  // namespace tdf
