#pragma once
/// Disjoint sets over 0..n-1 as a parent array (parent[i] == i at a root): the one find for the
/// UV atlas's charts, the mesh's UV charts and the tangent frames shared across seams.
#include <cstddef>
#include <vector>

namespace tdf {

/// The root of `x`'s set, halving the path on the way (each visited entry then points to its
/// grandparent).
inline int find_root(std::vector<int>& parent, int x) {
    while (parent[std::size_t(x)] != x) x = parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
    return x;
}

}  // namespace tdf
