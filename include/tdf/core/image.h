#pragma once
/// A float image: `width` x `height` pixels of `channels` interleaved floats, row-major,
/// row 0 = top of the picture (docs/conventions.md). Values are linear, unclamped.
#include <tdf/core/default_init_allocator.h>

#include <cstddef>
#include <string>
#include <vector>

namespace tdf {

/// An image's values. Its allocator leaves new floats unwritten, so a large image is zero-filled
/// (or filled) by every core rather than by std::vector on one thread.
using ImageValues = std::vector<float, DefaultInitAllocator<float>>;

class Image {
public:
    Image() = default;
    /// Every value `fill` (written in parallel when the image is large).
    Image(int width, int height, int channels, float fill = 0.0f);
    /// For an image whose every value the caller writes next: allocated, nothing written.
    struct Uninitialized {};
    Image(int width, int height, int channels, Uninitialized);

    int width() const { return m_width; }
    int height() const { return m_height; }
    int channels() const { return m_channels; }
    bool empty() const { return m_data.empty(); }
    std::size_t pixel_count() const { return std::size_t(m_width) * std::size_t(m_height); }

    float* pixel(int x, int y) { return &m_data[index(x, y)]; }
    const float* pixel(int x, int y) const { return &m_data[index(x, y)]; }
    float& at(int x, int y, int c) { return m_data[index(x, y) + std::size_t(c)]; }
    float at(int x, int y, int c) const { return m_data[index(x, y) + std::size_t(c)]; }

    float* data() { return m_data.data(); }
    const float* data() const { return m_data.data(); }
    ImageValues& values() { return m_data; }
    const ImageValues& values() const { return m_data; }

    /// Pixels [first, first + count) copied into a new image with `count` channels.
    Image channel_range(int first, int count) const;
    /// True when every value is finite.
    bool all_finite() const;

private:
    std::size_t index(int x, int y) const {
        return (std::size_t(y) * std::size_t(m_width) + std::size_t(x)) * std::size_t(m_channels);
    }

    int m_width = 0;
    int m_height = 0;
    int m_channels = 0;
    ImageValues m_data;
};

}  // namespace tdf
