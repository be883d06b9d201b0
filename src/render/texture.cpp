#include <tdf/core/error.h>
#include <tdf/core/force_inline.h>
#include <tdf/core/parallel.h>
#include <tdf/core/simd_clones.h>
#include <tdf/render/texture.h>

#include <algorithm>
#include <cmath>

#include "texture_lanes.h"

namespace tdf {

namespace {
// The footprint of a lookup at uv: texel centres at (k + 0.5) / size, v up, wrap addressing (one
// addressing for lookups and their taps).
TDF_FORCE_INLINE BilinearFootprint wrapped_footprint(const Image& img, Vec2f uv) {
    const TexelPoint t = uv_to_texel(uv.x, uv.y, img.width(), img.height());
    return bilinear_footprint(t.x, t.y, img.width(), img.height(), Addressing::Wrap);
}
}  // namespace


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
    rebuild_levels();
}

MipTexture::MipTexture(const Image& image) : MipTexture(Image(image)) {}

MipTexture::MipTexture(Image&& image) {
    if (image.empty()) throw_error("cannot build a texture from an empty image");
    if (image.channels() > kMaxTextureChannels)
        throw_error("textures have at most {} channels, this image has {}", kMaxTextureChannels, image.channels());
    m_levels.push_back(std::move(image));
    restore_levels();
}

void MipTexture::rebuild_levels() {
    for (std::size_t k = 1; k < m_levels.size(); ++k) downsample_box_into(m_levels[k - 1], m_levels[k]);
}

void MipTexture::drop_levels() {
    if (!m_levels.empty()) m_levels.resize(1);
}

void MipTexture::restore_levels() {
    TDF_CHECK(!m_levels.empty());
    while (m_levels.back().width() > 1 || m_levels.back().height() > 1)
        m_levels.push_back(downsample_box(m_levels.back()));
}

namespace {
// Fixed channel counts for the common maps: the renderer's inner loop.
TDF_FORCE_INLINE void blend_level(const Image& img, const BilinearFootprint& f, float* out) {
    switch (img.channels()) {
        case 3: blend_footprint<3>(img, f, out); break;
        case 4: blend_footprint<4>(img, f, out); break;
        case 1: blend_footprint<1>(img, f, out); break;
        default: blend_footprint(img, f, out); break;
    }
}

// The trilinear blend: level l0 already in `out`, level l0 + 1 in `next`.
TDF_FORCE_INLINE void lerp_levels(int channels, float frac, const float* next, float* out) {
    for (int k = 0; k < channels; ++k) out[k] += frac * (next[k] - out[k]);
}
}  // namespace

void MipTexture::sample_level(int level, Vec2f uv, float* out) const {
    const Image& img = m_levels[std::size_t(level)];
    blend_level(img, wrapped_footprint(img, uv), out);
}

void MipTexture::sample_bilinear(Vec2f uv, float* out) const { sample_level(0, uv, out); }

namespace {
// The major eigenvalue of J^T J, J's columns in level-0 texels per pixel of a w x h texture (the
// sign of dv does not change J^T J). Shared by the single and the batched LOD, so both give the
// same bits.
TDF_FORCE_INLINE float lod_major(Vec2f duv_dx, Vec2f duv_dy, float w, float h) {
    const float ax = duv_dx.x * w, ay = duv_dx.y * h;
    const float bx = duv_dy.x * w, by = duv_dy.y * h;
    const float a = ax * ax + ay * ay, c = bx * bx + by * by, b = ax * bx + ay * by;
    const float half_diff = 0.5f * (a - c);
    return 0.5f * (a + c) + std::sqrt(half_diff * half_diff + b * b);
}
TDF_FORCE_INLINE float lod_of_major(float major) { return major > 0.f ? 0.5f * std::log2(major) : -1e30f; }
}  // namespace

float MipTexture::level_of_detail(Vec2f duv_dx, Vec2f duv_dy) const {
    return lod_of_major(lod_major(duv_dx, duv_dy, float(width()), float(height())));
}

void MipTexture::sample_trilinear(Vec2f uv, Vec2f duv_dx, Vec2f duv_dy, float* out, int max_level) const {
    sample_trilinear_at(uv, level_of_detail(duv_dx, duv_dy), out, max_level);
}

namespace {
// The levels a trilinear lookup blends: l0, and l0 + 1 with weight frac when blend_next.
struct LevelPair {
    int l0;
    float frac;
    bool blend_next;
};
// The highest level a lookup may read.
TDF_FORCE_INLINE int top_level(int level_count, int max_level) {
    return max_level < 0 ? level_count - 1 : std::min(max_level, level_count - 1);
}
TDF_FORCE_INLINE LevelPair level_pair(float lod, int level_count, int max_level) {
    const int top = top_level(level_count, max_level);
    if (!(lod > 0.f)) lod = 0.f;  // also catches NaN
    lod = std::min(lod, float(top));
    const int l0 = int(lod);
    const float frac = lod - float(l0);
    return {l0, frac, frac > 0.f && l0 + 1 <= top};
}
}  // namespace

namespace {
// One trilinear lookup (sample_trilinear_at), inlined into the batched loop's clones too.
TDF_FORCE_INLINE void trilinear_at(const std::vector<Image>& levels, Vec2f uv, float lod, float* out, int max_level) {
    const LevelPair p = level_pair(lod, int(levels.size()), max_level);
    const Image& first = levels[std::size_t(p.l0)];
    blend_level(first, wrapped_footprint(first, uv), out);
    if (!p.blend_next) return;
    float next[kMaxTextureChannels];
    const Image& second = levels[std::size_t(p.l0 + 1)];
    blend_level(second, wrapped_footprint(second, uv), next);
    lerp_levels(levels[0].channels(), p.frac, next, out);
}
}  // namespace

void MipTexture::sample_trilinear_at(Vec2f uv, float lod, float* out, int max_level) const {
    trilinear_at(m_levels, uv, lod, out, max_level);
}

namespace {
// Both lookups of sample_trilinear_pair_at; C > 0 fixes both channel counts (3: RGB albedo and
// XYZ tactile map, the renderer's inner loop), 0 reads them from the images.
template <int C>
TDF_FORCE_INLINE void sample_pair(const std::vector<Image>& a, const std::vector<Image>& b, Vec2f uv, LevelPair p, float* out_a,
                 float* out_b) {
    const auto blend = [](const Image& img, const BilinearFootprint& f, float* out) {
        if constexpr (C > 0)
            blend_footprint<C>(img, f, out);
        else
            blend_level(img, f, out);
    };
    const BilinearFootprint f0 = wrapped_footprint(a[std::size_t(p.l0)], uv);
    blend(a[std::size_t(p.l0)], f0, out_a);
    blend(b[std::size_t(p.l0)], f0, out_b);
    if (!p.blend_next) return;
    const std::size_t l1 = std::size_t(p.l0 + 1);
    const BilinearFootprint f1 = wrapped_footprint(a[l1], uv);
    float next_a[kMaxTextureChannels], next_b[kMaxTextureChannels];
    blend(a[l1], f1, next_a);
    blend(b[l1], f1, next_b);
    lerp_levels(C > 0 ? C : a[0].channels(), p.frac, next_a, out_a);
    lerp_levels(C > 0 ? C : b[0].channels(), p.frac, next_b, out_b);
}
}  // namespace

void MipTexture::sample_trilinear_pair_at(const MipTexture& other, Vec2f uv, float lod, float* out,
                                          float* other_out, int max_level) const {
    TDF_CHECK(other.width() == width() && other.height() == height());
    const LevelPair p = level_pair(lod, level_count(), max_level);
    if (channels() == 3 && other.channels() == 3)
        sample_pair<3>(m_levels, other.m_levels, uv, p, out, other_out);
    else
        sample_pair<0>(m_levels, other.m_levels, uv, p, out, other_out);
}

namespace {
// Point i's c channels from `texel` into planes: out[k * plane + i].
TDF_FORCE_INLINE void put_planes(const float* texel, std::size_t c, float* out, std::size_t plane,
                                 std::size_t i) {
    for (std::size_t k = 0; k < c; ++k) out[k * plane + i] = texel[k];
}

// The gather kernel for this CPU (texture_lanes.h), or none: the AVX-512 one where the build's
// SIMD list has AVX-512 and the CPU too, else the AVX2 one likewise.
using PairKernel = void (*)(texture_lanes::PairLookups&);
PairKernel pair_kernel() {
    static const PairKernel kernel = []() -> PairKernel {
#if TDF_TEXTURE_LANES_AVX512
        if (__builtin_cpu_supports("avx512f")) return &texture_lanes::sample_pairs_avx512;
#endif
#if TDF_TEXTURE_LANES_AVX2
        if (__builtin_cpu_supports("avx2")) return &texture_lanes::sample_pairs_avx2;
#endif
        return nullptr;
    }();
    return kernel;
}
}  // namespace

// Compiled for AVX-512, AVX2 and the x86-64 baseline, picked at load time (GCC target_clones):
// the LODs' arithmetic vectorises, and the footprints use the instruction sets' rounding. Every
// clone gives sample_trilinear_pair_at's bits: the same operations in the same order, no FMA
// contraction in this file (src/CMakeLists.txt), and the same glibc log2f. Two RGB maps go to the
// gather kernel where there is one; the points it leaves take the scalar path like all others.
TDF_SIMD_CLONES
void MipTexture::sample_trilinear_pairs(const MipTexture& other, std::size_t n, const float* covered,
                                        const UvLanes& points, float* lod, float* out, float* other_out,
                                        std::size_t plane, int max_level) const {
    TDF_CHECK(other.width() == width() && other.height() == height() && plane >= n);
    const float w = float(width()), h = float(height());
    for (std::size_t i = 0; i < n; ++i) lod[i] = lod_major(points.duv_dx(i), points.duv_dy(i), w, h);
    for (std::size_t i = 0; i < n; ++i)
        if (covered[i] > 0.f) lod[i] = lod_of_major(lod[i]);
    const int levels = level_count();
    const std::size_t ca = std::size_t(channels()), cb = std::size_t(other.channels());
    const bool rgb = ca == 3 && cb == 3;
    const auto scalar = [&](std::size_t i) {
        const LevelPair p = level_pair(lod[i], levels, max_level);
        float a[kMaxTextureChannels], b[kMaxTextureChannels];
        if (rgb)
            sample_pair<3>(m_levels, other.m_levels, points.uv(i), p, a, b);
        else
            sample_pair<0>(m_levels, other.m_levels, points.uv(i), p, a, b);
        put_planes(a, ca, out, plane, i);
        put_planes(b, cb, other_out, plane, i);
    };
    constexpr std::size_t kMaxLevels = 32;  // a 2^31-texel side has 32 levels
    const PairKernel kernel = rgb && m_levels.size() <= kMaxLevels ? pair_kernel() : nullptr;
    if (!kernel) {
        for (std::size_t i = 0; i < n; ++i)
            if (covered[i] > 0.f) scalar(i);
        return;
    }
    texture_lanes::PairLevel table[kMaxLevels];
    for (std::size_t k = 0; k < m_levels.size(); ++k)
        table[k] = {m_levels[k].data(), other.m_levels[k].data(), m_levels[k].width(), m_levels[k].height()};
    // Chunks of a tile's size: the list of points left to the scalar path lives on the stack.
    constexpr std::size_t kChunk = 256;
    std::uint32_t left[kChunk];
    for (std::size_t start = 0; start < n; start += kChunk) {
        texture_lanes::PairLookups q;
        q.n = std::min(kChunk, n - start);
        q.covered = covered + start;
        q.u = points.u + start;
        q.v = points.v + start;
        q.lod = lod + start;
        q.levels = table;
        q.top = top_level(levels, max_level);
        q.out_a = out + start;
        q.out_b = other_out + start;
        q.plane = plane;
        q.left = left;
        kernel(q);
        for (std::size_t k = 0; k < q.left_count; ++k) scalar(start + left[k]);
    }
}

// Compiled like sample_trilinear_pairs, for the same reasons; the bits of sample_trilinear_at.
TDF_SIMD_CLONES
void MipTexture::sample_trilinear_many(std::size_t n, const float* covered, const UvLanes& points,
                                       float uv_scale, float lod_offset, float* lod, float* out,
                                       std::size_t plane, int max_level) const {
    TDF_CHECK(plane >= n);
    const float w = float(width()), h = float(height());
    for (std::size_t i = 0; i < n; ++i) lod[i] = lod_major(points.duv_dx(i), points.duv_dy(i), w, h);
    for (std::size_t i = 0; i < n; ++i)
        if (covered[i] > 0.f) lod[i] = lod_of_major(lod[i]) + lod_offset;
    const std::size_t c = std::size_t(channels());
    for (std::size_t i = 0; i < n; ++i) {
        if (!(covered[i] > 0.f)) continue;
        float texel[kMaxTextureChannels];
        trilinear_at(m_levels, points.uv(i) * uv_scale, lod[i], texel, max_level);
        put_planes(texel, c, out, plane, i);
    }
}

namespace {
// The four bilinear taps of `level` at uv, exactly as sample_level addresses them.
void add_level_taps(const Image& img, int level, Vec2f uv, float scale, TrilinearTaps& taps) {
    const int w = img.width();
    const BilinearFootprint f = wrapped_footprint(img, uv);
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
    const LevelPair p = level_pair(lod, level_count(), max_level);
    taps.count = 0;
    if (!p.blend_next) {
        add_level_taps(m_levels[std::size_t(p.l0)], p.l0, uv, 1.0f, taps);
        return;
    }
    add_level_taps(m_levels[std::size_t(p.l0)], p.l0, uv, 1.0f - p.frac, taps);
    add_level_taps(m_levels[std::size_t(p.l0 + 1)], p.l0 + 1, uv, p.frac, taps);
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
