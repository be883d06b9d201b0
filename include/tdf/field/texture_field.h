#pragma once
/// The texture field: a hash-grid encoding of the surface point followed by three linear heads
/// (spec 4.1): albedo = sigmoid(W_c e + b_c), tangent-space normal = normalize(tanh(W_n e + b_n)
/// + (0,0,1)) and optional part-label logits W_l e + b_l.
///
/// All parameters live in ONE flat float vector (grid first, then the heads, see
/// `parameter_blocks()`), so the optimizer and checkpoints treat the field as a plain array.
/// Forward and backward are hand-written, parallel, and allocation-free after the first call.
#include <tdf/core/vec.h>
#include <tdf/field/hash_grid.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tdf {

/// How world positions become grid coordinates.
enum class FieldInput {
    /// Default: the domain's bounding box, made cubic (longest side) and grown by `margin` on
    /// every side, maps to [0,1]^3, so the whole grid resolution covers the object.
    BoundingBox,
    /// Matches reference: raw world coordinates, negative values wrap around (spec 4.1).
    RawWrapped,
};

/// The field's hyper-parameters; defaults are the reference's (spec 4.1).
struct FieldConfig {
    HashGridConfig grid;
    FieldInput input = FieldInput::BoundingBox;
    /// Fraction of the longest bounding-box side added on every side (BoundingBox input only).
    float margin = 0.05f;
    /// Evaluate the part-label head. Its 66 parameters always exist (as in the reference);
    /// when false, `label` outputs are 0 and `d_label` is ignored.
    bool labels = false;
};

/// World-space axis-aligned box of the object the field textures (usually the mesh's bounds).
struct FieldDomain {
    Vec3f lower;
    Vec3f upper;
};

/// Per-point field outputs (array-of-structs: one point's outputs share a cache line).
struct FieldOutputs {
    Vec3f albedo;    ///< linear RGB in (0,1)
    Vec3f normal;    ///< unit tangent-space normal, z >= 0 (x = tangent, y = N x T, z = N)
    float label[2];  ///< part logits (part A = class 0); 0 when labels are disabled
};

/// dL/d(outputs) for one point, same layout as FieldOutputs.
struct FieldOutputGrads {
    Vec3f d_albedo;
    Vec3f d_normal;
    float d_label[2];
};

/// A named range of the flat parameter vector.
struct ParameterBlock {
    std::string name;  ///< "grid", "albedo.weight", "albedo.bias", "normal.weight", ...
    std::size_t offset = 0;
    std::size_t count = 0;
};

class TextureField;

/// The encodings that TextureField::evaluate() computed for a batch of points, kept so that
/// backward() for the same points and parameters skips its own forward pass (the gather from
/// the grid, about a third of an iteration's field time). Holds feature_count() floats per
/// point: 128 bytes for the defaults, 333 MB for the 2.6 M points of one default iteration.
/// The buffer grows to the largest batch and is reused, so a training loop allocates once.
class FieldCache {
public:
    /// Points of the evaluate() call that filled the cache (0 when empty).
    std::size_t point_count() const { return m_points; }
    /// Empties the cache and frees its memory.
    void clear();

private:
    friend class TextureField;
    std::vector<float> m_features;  // per encode block: feature-major encodings
    std::size_t m_points = 0;
    const TextureField* m_field = nullptr;
};

class TextureField {
public:
    /// Number of head outputs: albedo 3, normal 3, label 2 (the reference's channel order).
    static constexpr int kOutputs = 8;
    /// Points per fixed work chunk. Chunks depend only on the point count, never on the thread
    /// count, which makes backward() bit-identical on any number of threads.
    static constexpr std::size_t kChunk = 1024;

    /// Builds the field and initializes it from `seed`: grid entries U[-1e-4, 1e-4] (tcnn),
    /// head weights and biases U(-1/sqrt(F), 1/sqrt(F)) with F = 32 features (PyTorch Linear).
    /// Throws tdf::Error for an invalid config or an empty/non-finite domain.
    TextureField(const FieldConfig& config, const FieldDomain& domain, std::uint64_t seed);

    const FieldConfig& config() const { return m_config; }
    const HashGrid& grid() const { return m_grid; }
    /// Length of the encoding (32 for the defaults).
    int feature_count() const { return m_grid.feature_count(); }

    /// 953,608 for the defaults (953,344 grid + 264 heads).
    std::size_t parameter_count() const { return m_parameters.size(); }
    /// The flat parameter vector; the optimizer updates it in place (do not resize).
    std::vector<float>& parameters() { return m_parameters; }
    const std::vector<float>& parameters() const { return m_parameters; }
    /// Replaces all parameters (resume from a checkpoint); throws tdf::Error naming `what` when
    /// the count differs from parameter_count() (a checkpoint of another field configuration).
    void set_parameters(const std::vector<float>& values, const std::string& what);
    /// Named ranges: "grid", then "<head>.weight" (rows x feature_count, row-major, torch
    /// layout) and "<head>.bias" for head in albedo, normal, label.
    const std::vector<ParameterBlock>& parameter_blocks() const { return m_blocks; }
    /// The block called `name`; throws tdf::Error when there is none.
    const ParameterBlock& parameter_block(const std::string& name) const;

    /// Grid coordinates of world point `p` under the configured input mapping.
    Vec3f to_grid(Vec3f p) const { return (p - m_grid_origin) * m_grid_scale; }

    /// The encoding of world point `p` (feature_count() floats).
    void encode(Vec3f p, float* features) const;

    /// Forward pass for `n` world points, in parallel; writes out[0..n). Thread-safe.
    void evaluate(const Vec3f* points, std::size_t n, FieldOutputs* out) const;

    /// evaluate() that also keeps the encodings in `cache` (overwriting what it held) for a
    /// following backward(points, grads, n, gradient, cache). Same outputs, bit for bit.
    /// Thread-safe for distinct caches.
    void evaluate(const Vec3f* points, std::size_t n, FieldOutputs* out, FieldCache& cache) const;

    /// Adds dL/d(parameters) for `n` world points with upstream gradients `grads` to
    /// `gradient` (resized to parameter_count() and zero-filled when it has another size;
    /// otherwise accumulated into). Recomputes the forward pass. Deterministic: the result is
    /// bit-identical for any thread count. Points with all-zero gradients may simply be left
    /// out by the caller. Parallel inside; do not call concurrently on the same field (it
    /// reuses internal scratch buffers, allocated on first use).
    void backward(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                  std::vector<float>& gradient) const;

    /// backward() reading the encodings from `cache` instead of recomputing them: the caller
    /// guarantees that evaluate(points, n, out, cache) was the last call that filled `cache`,
    /// for the same `points` and with the parameters unchanged since (call it before the
    /// optimizer step). Bit-identical to backward() without a cache. Throws tdf::Error when the
    /// cache was filled by another field or holds another point count.
    void backward(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                  std::vector<float>& gradient, const FieldCache& cache) const;

private:
    // `cache`: encodings per encode block (evaluate writes them, backward reads them), or null.
    void evaluate_impl(const Vec3f* points, std::size_t n, FieldOutputs* out, float* cache) const;
    void backward_impl(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                       std::vector<float>& gradient, const float* cache) const;

    struct Scratch {
        std::vector<float> d_features;     // feature-major dL/d(encoding) of one block
        std::vector<float> coords;         // grid coordinates of one block, structure-of-arrays
        std::vector<float> head_partials;  // per-chunk head gradients
    };

    FieldConfig m_config;
    HashGrid m_grid;
    Vec3f m_grid_origin;
    float m_grid_scale = 1.0f;
    std::vector<float> m_parameters;
    std::vector<ParameterBlock> m_blocks;
    std::size_t m_head_offset = 0;  // first head parameter (albedo.weight)
    mutable Scratch m_scratch;
};

}  // namespace tdf
