#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <vector>

using namespace tdf;

// Every task runs exactly once, tasks may run parallel loops of their own, and the call returns
// only when all have finished.
TEST(ParallelTasks, RunsEveryTaskOnceWithNestedLoops) {
    std::vector<long> sums(5, 0);
    std::vector<std::function<void()>> tasks;
    for (std::size_t t = 0; t < sums.size(); ++t)
        tasks.push_back([&sums, t] {
            std::vector<long> values(1000);
            parallel_for(values.size(), 64, [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i) values[i] = long(i * (t + 1));
            });
            for (long v : values) sums[t] += v;
        });
    parallel_tasks(tasks);
    for (std::size_t t = 0; t < sums.size(); ++t) EXPECT_EQ(sums[t], 499500L * long(t + 1)) << "task " << t;
    parallel_tasks({});  // nothing to do is fine
}

// A task's error reaches the caller (a failed file write must not pass silently).
TEST(ParallelTasks, RethrowsATasksError) {
    std::atomic<int> ran{0};
    const std::vector<std::function<void()>> tasks = {[&] { ++ran; },
                                                      [] { throw_error("cannot write 'x.png': disk full"); }};
    EXPECT_THROW(parallel_tasks(tasks), Error);
    EXPECT_LE(ran.load(), 1);
}

// parallel_copy and parallel_fill cover every item across several chunks (the sizes are not
// multiples of the chunk) and nothing past the end.
TEST(ParallelCopy, CopiesAndFillsEveryItemAndNoMore) {
    for (const std::size_t count : {std::size_t(0), std::size_t(7), std::size_t(300001)}) {
        std::vector<float> from(count), to(count + 1, -1.0f);
        for (std::size_t i = 0; i < count; ++i) from[i] = float(i) * 0.5f;
        parallel_copy(from.data(), count, to.data());
        for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(to[i], from[i]) << count << " items, item " << i;
        EXPECT_EQ(to[count], -1.0f) << "written past the end";
        parallel_fill(to.data(), count, 3.0f);
        for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(to[i], 3.0f) << count << " items, item " << i;
        EXPECT_EQ(to[count], -1.0f) << "filled past the end";
    }
}
