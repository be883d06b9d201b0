#include <tdf/core/parallel.h>

#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#include <tbb/task_arena.h>

#include <cstdlib>
#include <string>

namespace tdf {

struct ThreadLimit::Impl {
    std::unique_ptr<tbb::global_control> control;
};

namespace {
int threads_from_environment() {
    if (const char* s = std::getenv("SLURM_CPUS_PER_TASK")) {
        int n = std::atoi(s);
        if (n > 0) return n;
    }
    return 0;
}
}  // namespace

ThreadLimit::ThreadLimit(int threads) : m_impl(std::make_unique<Impl>()) {
    if (threads <= 0) threads = threads_from_environment();
    if (threads > 0)
        m_impl->control = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, std::size_t(threads));
}

ThreadLimit::~ThreadLimit() = default;

int ThreadLimit::current() {
    return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

void parallel_for(std::size_t count, std::size_t grain,
                  const std::function<void(std::size_t, std::size_t)>& body) {
    if (count == 0) return;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, grain == 0 ? 1 : grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

void parallel_tasks(const std::vector<std::function<void()>>& tasks) {
    tbb::task_group group;
    for (const auto& task : tasks) group.run([&task] { task(); });
    group.wait();
}

void parallel_for_tiles(int width, int height, int tile,
                        const std::function<void(int, int, int, int)>& body) {
    parallel_for_tiles(width, height, tile, tile, body);
}

void parallel_for_tiles(int width, int height, int tile_width, int tile_height,
                        const std::function<void(int, int, int, int)>& body) {
    if (width <= 0 || height <= 0) return;
    const int tiles_x = (width + tile_width - 1) / tile_width;
    const int tiles_y = (height + tile_height - 1) / tile_height;
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y, 1),
                      [&](const tbb::blocked_range<int>& r) {
                          for (int t = r.begin(); t != r.end(); ++t) {
                              const int x0 = (t % tiles_x) * tile_width, y0 = (t / tiles_x) * tile_height;
                              body(x0,
                                   y0,
                                   std::min(x0 + tile_width, width),
                                   std::min(y0 + tile_height, height));
                          }
                      });
}

}  // namespace tdf
