#include <tdf/core/image.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace tdf {

Image::Image(int width, int height, int channels, Uninitialized)
    : m_width(width), m_height(height), m_channels(channels) {
    TDF_CHECK(width >= 0 && height >= 0 && channels >= 0);
    m_data.resize(std::size_t(width) * std::size_t(height) * std::size_t(channels));
}

Image::Image(int width, int height, int channels, float fill)
    : Image(width, height, channels, Uninitialized{}) {
    // Images of the training loop are megabytes, allocated every iteration: filled on one
    // thread, their zeroing was a tenth of a refinement iteration's wall time.
    parallel_fill(m_data.data(), m_data.size(), fill);
}

Image Image::channel_range(int first, int count) const {
    TDF_CHECK(first >= 0 && first + count <= m_channels);
    Image out(m_width, m_height, count);
    for (std::size_t p = 0; p < pixel_count(); ++p)
        for (int c = 0; c < count; ++c)
            out.m_data[p * std::size_t(count) + std::size_t(c)] =
                m_data[p * std::size_t(m_channels) + std::size_t(first + c)];
    return out;
}

bool Image::all_finite() const {
    // Exponent bits all ones = inf or NaN. Or-ing a flag over each chunk (no early exit)
    // vectorises, and the chunks are read side by side: validating a guidance request's
    // 512^2 images is then a memory-speed pass on every core.
    std::atomic<bool> bad{false};
    const float* v = m_data.data();
    parallel_for(m_data.size(), std::size_t(1) << 16, [&](std::size_t begin, std::size_t end) {
        std::uint32_t chunk_bad = 0;
        for (std::size_t i = begin; i < end; ++i) {
            std::uint32_t bits;
            std::memcpy(&bits, v + i, sizeof(bits));
            chunk_bad |= std::uint32_t((bits & 0x7f800000u) == 0x7f800000u);
        }
        if (chunk_bad) bad.store(true, std::memory_order_relaxed);
    });
    return !bad.load();
}

}  // namespace tdf
