#pragma once
/// All threading goes through this header (TBB underneath).
///
/// Determinism rule: parallel work either writes disjoint outputs (per pixel, per texel) or
/// reduces per-chunk partial results in chunk order. Chunks are fixed by the problem size,
/// never by the thread count, so results are bit-identical on 1 and N threads.
#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

namespace tdf {

/// Limits every parallel loop to `threads` worker threads while alive (0 = all cores).
/// `tdf --threads N` holds one for the whole run; SLURM_CPUS_PER_TASK is honoured when
/// no explicit count is given.
class ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;
    /// The number of threads parallel loops may use now.
    static int current();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Calls `body(begin, end)` over [0, count) in chunks of at most `grain` items, in parallel.
void parallel_for(std::size_t count, std::size_t grain,
                  const std::function<void(std::size_t begin, std::size_t end)>& body);

/// Calls `body(x0, y0, x1, y1)` for each `tile` x `tile` tile of a width x height image.
void parallel_for_tiles(int width, int height, int tile,
                        const std::function<void(int x0, int y0, int x1, int y1)>& body);
/// The same with `tile_width` x `tile_height` tiles.
void parallel_for_tiles(int width, int height, int tile_width, int tile_height,
                        const std::function<void(int x0, int y0, int x1, int y1)>& body);

/// Runs the independent `tasks` side by side (each may use parallel loops of its own) and returns
/// when all have finished; the first exception thrown by a task is rethrown.
void parallel_tasks(const std::vector<std::function<void()>>& tasks);

/// Copies `count` items from `from` to `to` (non-overlapping) on every core, and sets `count`
/// items to `value`: for the training loop's megabyte buffers, where a copy on one thread leaves
/// the other cores waiting. Up to one chunk stays on the calling thread.
constexpr std::size_t kCopyChunk = std::size_t(1) << 16;
template <typename T>
void parallel_copy(const T* from, std::size_t count, T* to) {
    if (count <= kCopyChunk) {
        std::copy(from, from + count, to);
        return;
    }
    parallel_for(count, kCopyChunk, [=](std::size_t begin, std::size_t end) {
        std::copy(from + begin, from + end, to + begin);
    });
}
template <typename T>
void parallel_fill(T* to, std::size_t count, const T& value) {
    if (count <= kCopyChunk) {
        std::fill(to, to + count, value);
        return;
    }
    parallel_for(count, kCopyChunk, [=, &value](std::size_t begin, std::size_t end) {
        std::fill(to + begin, to + end, value);
    });
}

/// Number of fixed-size chunks [i*chunk, min((i+1)*chunk, count)) covering [0, count).
inline std::size_t chunk_count(std::size_t count, std::size_t chunk) {
    return (count + chunk - 1) / chunk;
}

}  // namespace tdf
