#pragma once
/// Seeded random numbers. Every random draw in tdf comes from an Rng derived from the run's
/// seed, so the same seed gives the same results on any thread count. Parallel code derives
/// one stream per work item with `Rng::stream(seed, item)` instead of sharing a generator.
#include <cstdint>

namespace tdf {

/// PCG32 (O'Neill 2014): small state that checkpoints as two integers.
class Rng {
public:
    explicit Rng(std::uint64_t seed = 0x853c49e6748fea9bULL, std::uint64_t stream = 0xda3e39cb94b95bdbULL);

    /// An independent generator for work item `item` of a run seeded with `seed`.
    static Rng stream(std::uint64_t seed, std::uint64_t item) { return Rng(seed, item * 2 + 1); }

    std::uint32_t next_u32();
    /// Uniform in [0, 1).
    float uniform();
    /// Uniform in [lo, hi).
    float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
    /// Uniform integer in [lo, hi) (hi exclusive, like numpy randint).
    int uniform_int(int lo, int hi);
    /// Standard normal (Box-Muller).
    float normal();

    std::uint64_t state() const { return m_state; }
    std::uint64_t increment() const { return m_inc; }
    void restore(std::uint64_t state, std::uint64_t increment) {
        m_state = state;
        m_inc = increment;
    }

private:
    std::uint64_t m_state = 0;
    std::uint64_t m_inc = 0;
};

}  // namespace tdf
