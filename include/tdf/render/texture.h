#pragma once
/// A mip-mapped texture with nvdiffrast's sampling semantics (spec 3.7): texel centres at
/// (k + 0.5) / size, bilinear filtering, wrap addressing, and for trilinear filtering a LOD of
/// 0.5 log2 of the major eigenvalue of J^T J (J = d(texel coords)/d(pixel)).
///
/// UVs are tdf's (OBJ convention, v up): texel coordinates are x = u W - 0.5 and
/// y = (1 - v) H - 0.5, so v = 1 is the top row of the image (the reference's v' = 1 - v).
#include <tdf/core/image.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/vec.h>

#include <cstdint>
#include <vector>

namespace tdf {

/// The texels one trilinear lookup blends: at most 4 of each of two levels (MipTexture::taps).
struct TrilinearTaps {
    static constexpr int kMaxTaps = 8;
    int count = 0;
    int level[kMaxTaps] = {};
    std::uint32_t texel[kMaxTaps] = {};  ///< row-major texel index within that level
    float weight[kMaxTaps] = {};
};

/// Points to look up, one array per component: UVs (v up) and their derivatives per output pixel
/// (the renderer's G-buffer lanes).
struct UvLanes {
    const float* u;
    const float* v;
    const float* du_dx;
    const float* dv_dx;
    const float* du_dy;
    const float* dv_dy;
    Vec2f uv(std::size_t i) const { return {u[i], v[i]}; }
    Vec2f duv_dx(std::size_t i) const { return {du_dx[i], dv_dx[i]}; }
    Vec2f duv_dy(std::size_t i) const { return {du_dy[i], dv_dy[i]}; }
};

/// Largest channel count a MipTexture accepts (per-sample scratch lives on the stack).
constexpr int kMaxTextureChannels = 16;

class MipTexture {
public:
    MipTexture() = default;
    /// Builds the pyramid from `image` (any channel count, any size). Level k+1 is
    /// downsample_box(level k): max(1, floor(size_k / 2)) per axis, each texel the area-weighted
    /// box average of the level-k texels it covers (the 2x2 box filter of spec 3.7 for even sizes).
    explicit MipTexture(const Image& image);
    /// The same, taking the image as level 0 (no copy: a caller that keeps only the texture holds
    /// its base image once).
    explicit MipTexture(Image&& image);

    /// Rebuilds the pyramid from `image`, reusing the storage when the size and channel count are
    /// unchanged (an optimizer updates its maps every iteration without allocating).
    void assign(const Image& image);

    bool empty() const { return m_levels.empty(); }
    int channels() const { return m_levels.empty() ? 0 : m_levels[0].channels(); }
    int width() const { return m_levels.empty() ? 0 : m_levels[0].width(); }
    int height() const { return m_levels.empty() ? 0 : m_levels[0].height(); }
    int level_count() const { return int(m_levels.size()); }
    const Image& level(int k) const { return m_levels[std::size_t(k)]; }
    /// Level 0 to change in place (a learned map composed into the texture itself); call
    /// rebuild_levels() before the next lookup.
    Image& base_level() { return m_levels[0]; }
    /// Levels 1.. from level 0 again, as the constructor and assign() build them.
    void rebuild_levels();
    /// Frees levels 1.. (a third of the texture) for a step that reads only level 0; until
    /// restore_levels() brings them back, bit for bit, only level(0) may be read.
    void drop_levels();
    void restore_levels();

    /// Bilinear lookup on level 0; writes channels() floats to `out`.
    void sample_bilinear(Vec2f uv, float* out) const;
    /// Bilinear lookup on one level.
    void sample_level(int level, Vec2f uv, float* out) const;
    /// Trilinear ("linear-mipmap-linear") lookup. duv_dx / duv_dy are the UV derivatives per
    /// output pixel (tdf convention, v up). LOD is clamped to [0, max_level] where max_level = -1
    /// means the whole pyramid (training) and 5 is the visualizer's cap (spec 3.9).
    void sample_trilinear(Vec2f uv, Vec2f duv_dx, Vec2f duv_dy, float* out, int max_level = -1) const;
    /// The same with the LOD given (from level_of_detail() of a texture of the same size).
    void sample_trilinear_at(Vec2f uv, float lod, float* out, int max_level = -1) const;
    /// sample_trilinear_at of this texture into `out` and of `other` into `other_out` at the same
    /// uv, LOD and max_level, bit for bit; `other` must have this texture's width and height (an
    /// albedo and a tactile map laid alike), so both share one footprint per level.
    void sample_trilinear_pair_at(const MipTexture& other, Vec2f uv, float lod, float* out, float* other_out,
                                  int max_level = -1) const;
    /// sample_trilinear_pair_at for the n points with covered[i] > 0, each at the LOD
    /// level_of_detail(points.duv_dx(i), points.duv_dy(i)) (bit for bit), written in planes:
    /// channel k of point i to out[k * plane + i] and other_out[k * plane + i] (plane >= n);
    /// `lod` is n floats of scratch. Other points' values are left as they are. The whole tile at
    /// once lets the LODs' arithmetic vectorise, and two RGB maps are read with the CPU's gather
    /// instructions where it has them (AVX-512 or AVX2).
    void sample_trilinear_pairs(const MipTexture& other, std::size_t n, const float* covered,
                                const UvLanes& points, float* lod, float* out, float* other_out,
                                std::size_t plane, int max_level = -1) const;
    /// sample_trilinear_at(points.uv(i) * uv_scale, level_of_detail(points.duv_dx(i),
    /// points.duv_dy(i)) + lod_offset, ..., max_level) for the n points with covered[i] > 0, bit
    /// for bit (a map laid at a UV scale: its LOD moves by log2 of the scale), written in planes
    /// like sample_trilinear_pairs; `lod` is n floats of scratch.
    void sample_trilinear_many(std::size_t n, const float* covered, const UvLanes& points, float uv_scale,
                               float lod_offset, float* lod, float* out, std::size_t plane,
                               int max_level = -1) const;
    /// The texels and weights sample_trilinear_at(uv, lod, out, max_level) blends (same LOD
    /// clamping, same wrap addressing), for optimizers that need the adjoint (texture_gradient.h).
    /// Weights sum to 1.
    void taps(Vec2f uv, float lod, int max_level, TrilinearTaps& taps) const;
    /// The lookup from recorded taps: channels() floats; equal to sample_trilinear_at up to the
    /// order of float additions.
    void gather(const TrilinearTaps& taps, float* out) const;
    /// The LOD sample_trilinear() uses (before clamping); equal for textures of equal size.
    float level_of_detail(Vec2f duv_dx, Vec2f duv_dy) const;

private:
    std::vector<Image> m_levels;
};

// Each level is downsample_box() of the previous one; the pyramid's gradient goes back through
// downsample_box_adjoint() (both in core/image_ops.h).

}  // namespace tdf
