#include <tdf/render/texture.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

// For one axis: destination texel d covers source interval [d s, (d+1) s), s = src / dst.
// Each destination texel gets the (first index, weights) of the source texels it overlaps.
struct BoxTaps {
    std::vector<int> first;
    std::vector<int> count;
    std::vector<float> weights;  // flattened, kMaxTaps per destination texel
    static constexpr int kMaxTaps = 4;
};

BoxTaps box_taps(int src, int dst) {
    BoxTaps taps;
    taps.first.resize(std::size_t(dst));
    taps.count.resize(std::size_t(dst));
    taps.weights.assign(std::size_t(dst) * BoxTaps::kMaxTaps, 0.f);
    const double scale = double(src) / double(dst);
    for (int d = 0; d < dst; ++d) {
        const double lo = d * scale, hi = (d + 1) * scale;
        const int first = int(std::floor(lo));
        const int last = std::min(src - 1, int(std::ceil(hi)) - 1);
        taps.first[std::size_t(d)] = first;
        taps.count[std::size_t(d)] = last - first + 1;
        TDF_CHECK_LE(last - first + 1, BoxTaps::kMaxTaps);
        for (int s = first; s <= last; ++s) {
            const double overlap = std::min(hi, double(s + 1)) - std::max(lo, double(s));
            taps.weights[std::size_t(d) * BoxTaps::kMaxTaps + std::size_t(s - first)] = float(overlap / scale);
        }
    }
    return taps;
}

inline int wrap(int i, int n) {
    if ((n & (n - 1)) == 0) return i & (n - 1);  // power of two (two's complement handles i < 0)
    const int r = i % n;
    return r < 0 ? r + n : r;
}

// The texel column/row of floor(coordinate) with wrap addressing. Huge or non-finite UVs take
// a slow path so the int conversion never overflows.
inline int wrap_floor(float floored, int n) {
    if (std::fabs(floored) < 1e9f) return wrap(int(floored), n);
    if (!std::isfinite(floored)) return 0;
    return wrap(int(std::fmod(floored, float(n))), n);
}

// The two texel columns and rows a bilinear lookup at uv blends (texel centres at (k + 0.5) /
// size, v up, wrap addressing) and the blend weights: one addressing for lookups and their taps.
struct BilinearFootprint {
    int x0, x1, y0, y1;
    float ax, ay;
};
inline BilinearFootprint bilinear_footprint(const Image& img, Vec2f uv) {
    const int w = img.width(), h = img.height();
    const float x = uv.x * float(w) - 0.5f;
    const float y = (1.f - uv.y) * float(h) - 0.5f;
    const float fx0 = std::floor(x), fy0 = std::floor(y);
    BilinearFootprint f;
    f.ax = x - fx0, f.ay = y - fy0;
    f.x0 = wrap_floor(fx0, w), f.y0 = wrap_floor(fy0, h);
    f.x1 = f.x0 + 1 == w ? 0 : f.x0 + 1, f.y1 = f.y0 + 1 == h ? 0 : f.y0 + 1;
    return f;
}

}  // namespace

void downsample_box_into(const Image& src, Image& dst) {
    const int w = dst.width(), h = dst.height(), c = src.channels();
    const BoxTaps tx = box_taps(src.width(), w), ty = box_taps(src.height(), h);
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y) {
            for (int x = 0; x < w; ++x) {
                float* out = dst.pixel(x, int(y));
                for (int j = 0; j < ty.count[y]; ++j) {
                    const float wy = ty.weights[y * BoxTaps::kMaxTaps + std::size_t(j)];
                    for (int i = 0; i < tx.count[std::size_t(x)]; ++i) {
                        const float wxy = wy * tx.weights[std::size_t(x) * BoxTaps::kMaxTaps + std::size_t(i)];
                        const float* in = src.pixel(tx.first[std::size_t(x)] + i, ty.first[y] + j);
                        for (int k = 0; k < c; ++k) out[k] += wxy * in[k];
                    }
                }
            }
        }
    });
}

Image downsample_box(const Image& src) {
    Image dst(std::max(1, src.width() / 2), std::max(1, src.height() / 2), src.channels());
    downsample_box_into(src, dst);
    return dst;
}

void downsample_box_adjoint(const Image& coarse, Image& fine) {
    const int w = coarse.width(), h = coarse.height(), c = coarse.channels();
    TDF_CHECK(w == std::max(1, fine.width() / 2) && h == std::max(1, fine.height() / 2) && c == fine.channels());
    const BoxTaps tx = box_taps(fine.width(), w), ty = box_taps(fine.height(), h);
    // Fine rows receive from at most two coarse rows: parallel over coarse rows would race on the
    // shared fine row of odd sizes, so each task owns a range of coarse rows and the rows it
    // shares with its neighbour are written in a second, serial pass only when the size is odd.
    const bool exact_halves = fine.width() == 2 * w && fine.height() == 2 * h;
    const auto scatter_row = [&](std::size_t y) {
        for (int x = 0; x < w; ++x) {
            const float* g = coarse.pixel(x, int(y));
            for (int j = 0; j < ty.count[y]; ++j) {
                const float wy = ty.weights[y * BoxTaps::kMaxTaps + std::size_t(j)];
                for (int i = 0; i < tx.count[std::size_t(x)]; ++i) {
                    const float wxy = wy * tx.weights[std::size_t(x) * BoxTaps::kMaxTaps + std::size_t(i)];
                    float* out = fine.pixel(tx.first[std::size_t(x)] + i, ty.first[y] + j);
                    for (int k = 0; k < c; ++k) out[k] += wxy * g[k];
                }
            }
        }
    };
    if (exact_halves) {
        parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t y = y0; y < y1; ++y) scatter_row(y);
        });
    } else {
        for (std::size_t y = 0; y < std::size_t(h); ++y) scatter_row(y);
    }
}

void MipTexture::assign(const Image& image) {
    if (image.empty()) throw_error("cannot build a texture from an empty image");
    if (image.channels() > kMaxTextureChannels)
        throw_error("textures have at most {} channels, this image has {}", kMaxTextureChannels, image.channels());
    if (m_levels.empty() || m_levels[0].width() != image.width() || m_levels[0].height() != image.height() ||
        m_levels[0].channels() != image.channels()) {
        *this = MipTexture(image);
        return;
    }
    std::copy(image.values().begin(), image.values().end(), m_levels[0].values().begin());
    for (std::size_t k = 1; k < m_levels.size(); ++k) {
        Image& dst = m_levels[k];
        std::fill(dst.values().begin(), dst.values().end(), 0.0f);
        downsample_box_into(m_levels[k - 1], dst);
    }
}

MipTexture::MipTexture(const Image& image) {
    if (image.empty()) throw_error("cannot build a texture from an empty image");
    if (image.channels() > kMaxTextureChannels)
        throw_error("textures have at most {} channels, this image has {}", kMaxTextureChannels, image.channels());
    m_levels.push_back(image);
    while (m_levels.back().width() > 1 || m_levels.back().height() > 1)
        m_levels.push_back(downsample_box(m_levels.back()));
}

namespace {
// The four taps blended; C > 0 fixes the channel count at compile time for the common cases.
template <int C>
inline void blend(const float* p00, const float* p10, const float* p01, const float* p11, float ax, float ay,
                  int channels, float* out) {
    const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
    const int c = C > 0 ? C : channels;
    for (int k = 0; k < c; ++k) out[k] = w00 * p00[k] + w10 * p10[k] + w01 * p01[k] + w11 * p11[k];
}
}  // namespace

void MipTexture::sample_level(int level, Vec2f uv, float* out) const {
    const Image& img = m_levels[std::size_t(level)];
    const int w = img.width(), c = img.channels();
    const BilinearFootprint f = bilinear_footprint(img, uv);
    const int x0 = f.x0, x1 = f.x1, y0 = f.y0, y1 = f.y1;
    const float ax = f.ax, ay = f.ay;
    const float* row0 = img.data() + std::size_t(y0) * std::size_t(w) * std::size_t(c);
    const float* row1 = img.data() + std::size_t(y1) * std::size_t(w) * std::size_t(c);
    const float *p00 = row0 + x0 * c, *p10 = row0 + x1 * c, *p01 = row1 + x0 * c, *p11 = row1 + x1 * c;
    switch (c) {
        case 3: blend<3>(p00, p10, p01, p11, ax, ay, c, out); break;
        case 4: blend<4>(p00, p10, p01, p11, ax, ay, c, out); break;
        case 1: blend<1>(p00, p10, p01, p11, ax, ay, c, out); break;
        default: blend<0>(p00, p10, p01, p11, ax, ay, c, out); break;
    }
}

void MipTexture::sample_bilinear(Vec2f uv, float* out) const { sample_level(0, uv, out); }

float MipTexture::level_of_detail(Vec2f duv_dx, Vec2f duv_dy) const {
    // J columns in level-0 texels per pixel; the sign of dv does not change J^T J.
    const float w = float(width()), h = float(height());
    const float ax = duv_dx.x * w, ay = duv_dx.y * h;
    const float bx = duv_dy.x * w, by = duv_dy.y * h;
    const float a = ax * ax + ay * ay, c = bx * bx + by * by, b = ax * bx + ay * by;
    const float half_diff = 0.5f * (a - c);
    const float major = 0.5f * (a + c) + std::sqrt(half_diff * half_diff + b * b);
    return major > 0.f ? 0.5f * std::log2(major) : -1e30f;
}

void MipTexture::sample_trilinear(Vec2f uv, Vec2f duv_dx, Vec2f duv_dy, float* out, int max_level) const {
    sample_trilinear_at(uv, level_of_detail(duv_dx, duv_dy), out, max_level);
}

void MipTexture::sample_trilinear_at(Vec2f uv, float lod, float* out, int max_level) const {
    const int top = max_level < 0 ? level_count() - 1 : std::min(max_level, level_count() - 1);
    if (!(lod > 0.f)) lod = 0.f;  // also catches NaN
    lod = std::min(lod, float(top));
    const int l0 = int(lod);
    const float frac = lod - float(l0);
    sample_level(l0, uv, out);
    if (frac <= 0.f || l0 + 1 > top) return;
    const int c = channels();
    float next[kMaxTextureChannels];
    sample_level(l0 + 1, uv, next);
    for (int k = 0; k < c; ++k) out[k] += frac * (next[k] - out[k]);
}

namespace {
// The four bilinear taps of `level` at uv, exactly as sample_level addresses them.
void add_level_taps(const Image& img, int level, Vec2f uv, float scale, TrilinearTaps& taps) {
    const int w = img.width();
    const BilinearFootprint f = bilinear_footprint(img, uv);
    const int x0 = f.x0, x1 = f.x1, y0 = f.y0, y1 = f.y1;
    const float ax = f.ax, ay = f.ay;
    const auto add = [&](int tx, int ty, float weight) {
        const int k = taps.count++;
        taps.level[k] = level;
        taps.texel[k] = std::uint32_t(ty) * std::uint32_t(w) + std::uint32_t(tx);
        taps.weight[k] = scale * weight;
    };
    add(x0, y0, (1 - ax) * (1 - ay));
    add(x1, y0, ax * (1 - ay));
    add(x0, y1, (1 - ax) * ay);
    add(x1, y1, ax * ay);
}
}  // namespace

void MipTexture::taps(Vec2f uv, float lod, int max_level, TrilinearTaps& taps) const {
    const int top = max_level < 0 ? level_count() - 1 : std::min(max_level, level_count() - 1);
    if (!(lod > 0.f)) lod = 0.f;
    lod = std::min(lod, float(top));
    const int l0 = int(lod);
    const float frac = lod - float(l0);
    taps.count = 0;
    if (frac <= 0.f || l0 + 1 > top) {
        add_level_taps(m_levels[std::size_t(l0)], l0, uv, 1.0f, taps);
        return;
    }
    add_level_taps(m_levels[std::size_t(l0)], l0, uv, 1.0f - frac, taps);
    add_level_taps(m_levels[std::size_t(l0 + 1)], l0 + 1, uv, frac, taps);
}

namespace {
template <int C>
inline void gather_taps(const std::vector<Image>& levels, const TrilinearTaps& taps, int channels, float* out) {
    const int c = C > 0 ? C : channels;
    float sum[kMaxTextureChannels] = {};
    for (int t = 0; t < taps.count; ++t) {
        const float* texel = levels[std::size_t(taps.level[t])].data() + std::size_t(taps.texel[t]) * std::size_t(c);
        const float w = taps.weight[t];
        for (int k = 0; k < c; ++k) sum[k] += w * texel[k];
    }
    for (int k = 0; k < c; ++k) out[k] = sum[k];
}
}  // namespace

void MipTexture::gather(const TrilinearTaps& taps, float* out) const {
    if (channels() == 3)
        gather_taps<3>(m_levels, taps, 3, out);
    else
        gather_taps<0>(m_levels, taps, channels(), out);
}

}  // namespace tdf
