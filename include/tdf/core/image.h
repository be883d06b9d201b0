#pragma once
/// A float image: `width` x `height` pixels of `channels` interleaved floats, row-major,
/// row 0 = top of the picture (docs/conventions.md). Values are linear, unclamped.
#include <cstddef>
#include <string>
#include <vector>

namespace tdf {

class Image {
public:
    Image() = default;
    Image(int width, int height, int channels, float fill = 0.0f);

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
    std::vector<float>& values() { return m_data; }
    const std::vector<float>& values() const { return m_data; }

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
    std::vector<float> m_data;
};

}  // namespace tdf
