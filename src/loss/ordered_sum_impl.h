#pragma once
// Deterministic parallel sums for the losses: fixed chunks (independent of the thread count),
// one double partial per chunk, partials added in chunk order.
#include <tdf/core/parallel.h>

#include <cstddef>
#include <vector>

namespace tdf::detail {

constexpr std::size_t kLossChunk = 16384;

/// Sum over [0, count) of `range_sum(begin, end)` (which returns the double sum of its range
/// and may also write per-item outputs).
template <typename RangeSum>
double ordered_sum(std::size_t count, RangeSum&& range_sum) {
    const std::size_t chunks = chunk_count(count, kLossChunk);
    std::vector<double> partial(chunks, 0.0);
    parallel_for(chunks, 1, [&](std::size_t c0, std::size_t c1) {
        for (std::size_t c = c0; c < c1; ++c)
            partial[c] = range_sum(c * kLossChunk, std::min(count, (c + 1) * kLossChunk));
    });
    double sum = 0;
    for (const double p : partial) sum += p;
    return sum;
}

/// Calls `body(begin, end)` over [0, count) in parallel (elementwise work, disjoint writes).
template <typename Body>
void elementwise(std::size_t count, Body&& body) {
    parallel_for(count, kLossChunk, [&](std::size_t begin, std::size_t end) { body(begin, end); });
}

}  // namespace tdf::detail
