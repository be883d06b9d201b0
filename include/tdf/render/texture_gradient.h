#pragma once
/// The adjoint of MipTexture sampling, for optimizers that learn the texture itself
/// (texture-space optimization: what training renders see is the exported map).
///
/// A trilinear lookup is a weighted sum of at most 8 texels of two pyramid levels. `TrilinearTaps`
/// records them once per pixel (the same taps MipTexture::sample_trilinear_at blends, bit for bit),
/// so the forward value is `gather` of the taps and the backward pass adds weight x gradient to
/// each tap (`MipGradient::add`). Every pyramid level is the box average of the level below
/// (downsample_box), so `MipGradient::collapse` pushes each level's gradient down to its children
/// with the same box weights, coarse to fine, ending with dL/d(level-0 texel).
///
/// Determinism: `add` is meant for one thread at a time per MipGradient (callers scatter views in
/// a fixed order, or give independent maps to independent tasks); `collapse` is parallel over rows
/// with disjoint writes. Results are identical on any thread count.
#include <tdf/core/release.h>
#include <tdf/render/texture.h>

#include <cstdint>
#include <vector>

namespace tdf {

/// Gradient of a loss with respect to every texel of every level of a MipTexture's pyramid.
class MipGradient {
public:
    MipGradient() = default;
    /// Zero gradient shaped like `texture`'s pyramid, with `channels` channels per texel (0 = the
    /// texture's; more lets a caller accumulate extra per-texel sums, such as a curvature, through
    /// the same taps). Reuses its storage when the shape is unchanged.
    void reset(const MipTexture& texture, int channels = 0);
    /// Frees the pyramid (empty until the next reset): a caller between steps holds no gradient.
    void release() { tdf::release(m_levels); }
    bool empty() const { return m_levels.empty(); }
    /// Adds weight_k x grad to each tap (grad has channels() floats).
    void add(const TrilinearTaps& taps, const float* grad);
    /// Texel ranges splitting every level into `count` bands (for add_band).
    struct Bands {
        int count = 1;
        std::vector<std::uint32_t> edges;  ///< level l, band b: [edges[l (count+1) + b], ... + b + 1)
    };
    Bands bands(int count) const;
    /// add() restricted to the taps whose texel lies in band `band`. Tasks that each take one band
    /// and run over the same taps in the same order add into disjoint texels, and every texel gets
    /// its sums in that order: the same bits as add() on one thread, with the work spread.
    void add_band(const TrilinearTaps& taps, const float* grad, const Bands& bands, int band);
    /// Adds every other's gradient into this one (same shape); used to reduce per-task gradients
    /// in a fixed order.
    void accumulate(const MipGradient& other);
    /// Pushes every level's gradient down to level 0 (the adjoint of the box pyramid), frees the
    /// coarser levels, and returns level 0: dL/d(texel) of the base image, width x height x channels.
    /// The next add() needs a reset().
    const Image& collapse();
    int channels() const { return m_levels.empty() ? 0 : m_levels[0].channels(); }
    /// Level 0's gradient (after collapse(): of the base image); writable, so a caller can fold
    /// further terms into it.
    Image& level0() { return m_levels[0]; }
    const Image& level(int k) const { return m_levels[std::size_t(k)]; }

private:
    std::vector<Image> m_levels;
};

}  // namespace tdf
