#pragma once
/// The albedo and tangent-space normal maps the texture-space optimizer learns (issue 10): what
/// training renders sample is what the user gets. Per covered texel t of the atlas
///   albedo(t) = field albedo(p_t) + r_albedo(t),   normal(t) = field normal(p_t) + r_normal(t)
/// where p_t is the texel's surface point, the field is the hash grid + heads (3-D consistent,
/// low frequencies, 2^15 entries per level hold ~1 M values) and r is a per-texel residual (the
/// full resolution the 1024^2 maps need). Normals are left unnormalised in the map; lookups
/// renormalise per pixel (spec 3.1 step 5), exports per texel. Gutter texels copy their source
/// texel (TexelAtlas::fill_gutter) and the mip pyramids are box filters, as MipTexture builds them.
#include <tdf/field/texture_field.h>
#include <tdf/render/texture.h>
#include <tdf/train/texel_atlas.h>

#include <vector>

namespace tdf {

class LearnedMaps {
public:
    /// Residual values per covered texel: albedo RGB then normal XYZ.
    static constexpr int kResidualPerTexel = 6;

    /// Maps over `atlas` (borrowed; must outlive this). Residual zero, field not evaluated yet.
    explicit LearnedMaps(const TexelAtlas& atlas);

    const TexelAtlas& atlas() const { return *m_atlas; }
    std::vector<float>& residual() { return m_residual; }
    const std::vector<float>& residual() const { return m_residual; }

    /// Evaluates `field` at every texel's surface point; with `keep_encodings` keeps them for a
    /// following field_backward() (128 bytes per texel).
    void evaluate_field(const TextureField& field, bool keep_encodings = false);
    /// Sets the residual so that the maps equal `albedo` and `normal` (size x size, RGB) exactly
    /// on every covered texel: r = target - field (call after evaluate_field).
    void set_residual_to(const Image& albedo, const Image& normal);
    /// Composes field + residual into the level-0 maps, fills the gutter and rebuilds the mips.
    /// With albedo bounds set, each covered texel's albedo is first projected into them per
    /// channel and its residual moved with it (r = clamp(field + r) - field), so what training
    /// renders see, what the optimizer continues from and what is exported are the same values.
    void update();
    /// Per texel (size x size, RGB): the albedo may not leave [low, high] (albedo_range.h: the
    /// input's local range widened by a tolerance). Empty images remove the bound. The bound must
    /// hold the current maps' targets (the matching phase's end stays exact).
    void set_albedo_bounds(Image low, Image high);
    /// Frees what only update() and the optimizer read (the residual, the field's outputs, the
    /// bounds) once training is over; albedo() and normal() stay, update() refuses.
    void release_training_state();
    /// Frees what the field and the maps' level 0 give back bit for bit (the field's outputs at
    /// the texels and their encodings, the maps' levels above 0: 0.8 GB at 4096^2 maps) for a
    /// memory-heavy step between iterations, such as the export after matching. Until
    /// restore_derived() (same field parameters) only level 0 of albedo() and normal() may be read.
    void release_derived();
    void restore_derived(const TextureField& field, bool keep_encodings);
    /// Only the maps' levels (after release_training_state(), there are no outputs to restore).
    void restore_levels();

    const MipTexture& albedo() const { return m_albedo; }
    const MipTexture& normal() const { return m_normal; }
    /// Level 0 as exported: albedo clamped to [0, 1], normals renormalised per texel.
    Image export_albedo() const;
    Image export_normal() const;

    /// From dL/d(level-0 maps) (size x size, channels 0-2 used; the gutter's share is folded back
    /// into its source texels, so the images are modified): adds dL/d(residual) to `*d_residual`
    /// when given (resized to residual().size() when empty) and, when `d_field` is given, the
    /// per-texel upstream gradients of the field outputs (albedo, normal) in atlas texel order.
    /// Returns whether dL/d(residual) is finite: the Jacobi step needs no residual gradient (24
    /// bytes a texel at 4096^2 maps: 0.25 GB), only that check.
    bool backward(Image& d_albedo, Image& d_normal, std::vector<float>* d_residual,
                  std::vector<FieldOutputGrads>* d_field) const;
    /// Adds dL/d(residual) from gradients backward() has already folded (read only).
    void add_residual_gradient(const Image& d_albedo, const Image& d_normal, std::vector<float>& d_residual) const;
    /// The Jacobi (diagonal Gauss-Newton) update of the residual: `d_albedo` and `d_normal` hold
    /// per texel the gradient (channels 0-2) and the loss's curvature summed over the texel's
    /// footprint (channel 3), gutter already folded by backward(). Each texel with curvature
    /// moves by -step x gradient / (curvature + damping): the coverage-weighted mean of what its
    /// pixels ask for. Texels not seen this iteration do not move (no momentum: no speckle).
    /// `smoothing` passes of a [1 2 1] / 4 tent over the albedo's gradient and curvature first
    /// (`d_albedo` is modified) keep mip-level gradients from printing their blocks into level 0.
    void jacobi_step(Image& d_albedo, const Image& d_normal, float step, int smoothing);
    /// dL/d(field parameters) for per-texel output gradients from backward(), using the encodings
    /// of the last evaluate_field() (parameters unchanged since).
    void field_backward(const TextureField& field, const std::vector<FieldOutputGrads>& d_field,
                        std::vector<float>& gradient) const;
    /// The field's outputs at the texels from the last evaluate_field().
    const std::vector<FieldOutputs>& field_outputs() const { return m_field_outputs; }

private:
    const TexelAtlas* m_atlas;
    std::vector<float> m_residual;
    std::vector<FieldOutputs> m_field_outputs;
    FieldCache m_cache;
    Image m_albedo_low, m_albedo_high;  ///< empty: no bound
    MipTexture m_albedo, m_normal;  ///< level 0 is the composed map (update())
};

}  // namespace tdf
