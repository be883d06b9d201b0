#include <tdf/render/texture_gradient.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>

namespace tdf {

void MipGradient::reset(const MipTexture& texture, int channels) {
    if (channels <= 0) channels = texture.channels();
    const bool same = int(m_levels.size()) == texture.level_count() && !m_levels.empty() &&
                      m_levels[0].width() == texture.width() && m_levels[0].height() == texture.height() &&
                      m_levels[0].channels() == channels;
    if (!same) {
        m_levels.clear();
        for (int k = 0; k < texture.level_count(); ++k) {
            const Image& level = texture.level(k);
            m_levels.emplace_back(level.width(), level.height(), channels, 0.0f);
        }
        return;
    }
    for (Image& level : m_levels) std::fill(level.values().begin(), level.values().end(), 0.0f);
}

void MipGradient::add(const TrilinearTaps& taps, const float* grad) {
    const int c = channels();
    for (int t = 0; t < taps.count; ++t) {
        float* texel = m_levels[std::size_t(taps.level[t])].data() + std::size_t(taps.texel[t]) * std::size_t(c);
        const float w = taps.weight[t];
        for (int k = 0; k < c; ++k) texel[k] += w * grad[k];
    }
}

MipGradient::Bands MipGradient::bands(int count) const {
    TDF_CHECK(count >= 1);
    Bands b;
    b.count = count;
    for (const Image& level : m_levels) {
        const std::uint64_t texels = level.pixel_count();
        for (int k = 0; k <= count; ++k) b.edges.push_back(std::uint32_t(texels * std::uint64_t(k) / std::uint64_t(count)));
    }
    return b;
}

void MipGradient::add_band(const TrilinearTaps& taps, const float* grad, const Bands& bands, int band) {
    const int c = channels();
    for (int t = 0; t < taps.count; ++t) {
        const std::uint32_t* edge = bands.edges.data() + std::size_t(taps.level[t]) * std::size_t(bands.count + 1);
        if (taps.texel[t] < edge[band] || taps.texel[t] >= edge[band + 1]) continue;
        float* texel = m_levels[std::size_t(taps.level[t])].data() + std::size_t(taps.texel[t]) * std::size_t(c);
        const float w = taps.weight[t];
        for (int k = 0; k < c; ++k) texel[k] += w * grad[k];
    }
}

void MipGradient::accumulate(const MipGradient& other) {
    TDF_CHECK_EQ(other.m_levels.size(), m_levels.size());
    for (std::size_t k = 0; k < m_levels.size(); ++k) {
        ImageValues& dst = m_levels[k].values();
        const ImageValues& src = other.m_levels[k].values();
        TDF_CHECK_EQ(dst.size(), src.size());
        parallel_for(dst.size(), 1 << 16, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) dst[i] += src[i];
        });
    }
}

const Image& MipGradient::collapse() {
    TDF_CHECK(!m_levels.empty());
    // Each coarser level is read once, into the one below, then freed (a 4096^2 map's levels
    // above 0 hold a third of its gradient's memory).
    while (m_levels.size() > 1) {
        downsample_box_adjoint(m_levels.back(), m_levels[m_levels.size() - 2]);
        m_levels.pop_back();
    }
    return m_levels[0];
}

}  // namespace tdf
