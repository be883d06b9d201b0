#include <tdf/core/image.h>

#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

Image::Image(int width, int height, int channels, float fill)
    : m_width(width), m_height(height), m_channels(channels) {
    TDF_CHECK(width >= 0 && height >= 0 && channels >= 0);
    m_data.assign(std::size_t(width) * std::size_t(height) * std::size_t(channels), fill);
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
    for (float v : m_data)
        if (!std::isfinite(v)) return false;
    return true;
}

}  // namespace tdf
