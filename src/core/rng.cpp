#include <tdf/core/rng.h>

#include <cmath>

namespace tdf {

Rng::Rng(std::uint64_t seed, std::uint64_t stream) {
    m_state = 0;
    m_inc = (stream << 1u) | 1u;
    next_u32();
    m_state += seed;
    next_u32();
}

std::uint32_t Rng::next_u32() {
    const std::uint64_t old = m_state;
    m_state = old * 6364136223846793005ULL + m_inc;
    const auto xorshifted = std::uint32_t(((old >> 18u) ^ old) >> 27u);
    const auto rot = std::uint32_t(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

float Rng::uniform() {
    // 24 random bits: exactly representable, never 1.0.
    return float(next_u32() >> 8) * (1.0f / 16777216.0f);
}

int Rng::uniform_int(int lo, int hi) {
    if (hi <= lo) return lo;
    const std::uint32_t range = std::uint32_t(hi - lo);
    // Lemire's unbiased bounded draw without division in the common case.
    std::uint64_t m = std::uint64_t(next_u32()) * range;
    auto low = std::uint32_t(m);
    if (low < range) {
        const std::uint32_t threshold = (0u - range) % range;
        while (low < threshold) {
            m = std::uint64_t(next_u32()) * range;
            low = std::uint32_t(m);
        }
    }
    return lo + int(m >> 32);
}

float Rng::normal() {
    float u1 = uniform();
    while (u1 <= 0.0f) u1 = uniform();
    const float u2 = uniform();
    return std::sqrt(-2.0f * std::log(u1)) * std::cos(6.28318530717958647692f * u2);
}

}  // namespace tdf
