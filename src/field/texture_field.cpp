#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>

#include <cmath>

#include "multiversion_impl.h"

namespace tdf {

namespace {

// Points per backward block: the level-major dL/d(encoding) of one block is 32768 x 32 floats
// (4 MiB), small enough to stay cache-friendly, large enough that the per-level scatter
// tasks amortize their start.
constexpr std::size_t kBlockChunks = 32;

constexpr int kHeadRows[3] = {3, 3, 2};
const char* const kHeadNames[3] = {"albedo", "normal", "label"};

// torch F.normalize eps for the tangent-space normal (spec 4.1).
constexpr float kNormalEps = 1e-12f;

inline float sigmoid(float z) { return 1.0f / (1.0f + std::exp(-z)); }

}  // namespace

TextureField::TextureField(const FieldConfig& config, const FieldDomain& domain, std::uint64_t seed)
    : m_config(config), m_grid(config.grid) {
    if (config.input == FieldInput::BoundingBox) {
        if (!is_finite(domain.lower) || !is_finite(domain.upper))
            throw_error("field domain: bounding box is not finite");
        const Vec3f extent = domain.upper - domain.lower;
        const float side = std::max(extent.x, std::max(extent.y, extent.z));
        if (!(side > 0.0f)) throw_error("field domain: bounding box is empty (longest side {})", side);
        if (!(config.margin >= 0.0f) || !(config.margin <= 1.0f))
            throw_error("field.margin: {} is out of range 0..1", config.margin);
        const float padded = side * (1.0f + 2.0f * config.margin);
        m_grid_origin = (domain.lower + domain.upper) * 0.5f - Vec3f(1, 1, 1) * (0.5f * padded);
        m_grid_scale = 1.0f / padded;
    }

    const std::size_t features = std::size_t(m_grid.feature_count());
    std::size_t offset = 0;
    m_blocks.push_back({"grid", 0, m_grid.parameter_count()});
    offset += m_grid.parameter_count();
    m_head_offset = offset;
    for (int h = 0; h < 3; ++h) {
        const std::size_t rows = std::size_t(kHeadRows[h]);
        m_blocks.push_back({std::string(kHeadNames[h]) + ".weight", offset, rows * features});
        offset += rows * features;
        m_blocks.push_back({std::string(kHeadNames[h]) + ".bias", offset, rows});
        offset += rows;
    }
    m_parameters.resize(offset);

    Rng rng(seed);
    // Matches reference: tcnn grid init U[-1e-4, 1e-4]; torch Linear init U(-1/sqrt(in), 1/sqrt(in))
    // for weights and biases alike (spec 4.1).
    for (std::size_t i = 0; i < m_head_offset; ++i) m_parameters[i] = rng.uniform(-1e-4f, 1e-4f);
    const float bound = 1.0f / std::sqrt(float(features));
    for (std::size_t i = m_head_offset; i < offset; ++i) m_parameters[i] = rng.uniform(-bound, bound);
}

void TextureField::set_parameters(const std::vector<float>& values, const std::string& what) {
    if (values.size() != m_parameters.size())
        throw_error("{}: holds {} field parameters, but this field configuration has {}",
                    what,
                    values.size(),
                    m_parameters.size());
    m_parameters = values;
}

const ParameterBlock& TextureField::parameter_block(const std::string& name) const {
    for (const ParameterBlock& b : m_blocks)
        if (b.name == name) return b;
    throw_error("field: no parameter block named '{}'", name);
}

void TextureField::encode(Vec3f p, float* features) const {
    m_grid.encode(m_parameters.data(), to_grid(p), features);
}

namespace {

constexpr std::size_t kBatch = HashGrid::kBatch;
constexpr int kMaxFeatures = 2 * HashGrid::kMaxLevels;

// The three heads as one kOutputs x F layer (rows: albedo 3, normal 3, label 2), copied once per
// call from the flat parameters, which store each head torch-style as [weight rows x F | bias
// rows]. Label rows stay 0 when labels are off.
struct HeadMatrix {
    float weight[TextureField::kOutputs][kMaxFeatures] = {};
    float bias[TextureField::kOutputs] = {};
    int rows = 0;  // rows in use: 6, or 8 with labels
};

// Offsets (from the first head parameter) of each output row's weights and bias.
struct HeadRows {
    std::size_t weight[TextureField::kOutputs];
    std::size_t bias[TextureField::kOutputs];
};

HeadRows head_rows_of(int features) {
    HeadRows rows{};
    std::size_t offset = 0;
    int row = 0;
    for (int h = 0; h < 3; ++h) {
        for (int r = 0; r < kHeadRows[h]; ++r, ++row) {
            rows.weight[row] = offset + std::size_t(r * features);
            rows.bias[row] = offset + std::size_t(kHeadRows[h] * features + r);
        }
        offset += std::size_t(kHeadRows[h] * (features + 1));
    }
    return rows;
}

void build_head_matrix(const float* heads, int features, bool labels, HeadMatrix& m) {
    const HeadRows rows = head_rows_of(features);
    m.rows = labels ? TextureField::kOutputs : TextureField::kOutputs - 2;
    for (int r = 0; r < m.rows; ++r) {
        std::copy(heads + rows.weight[r], heads + rows.weight[r] + features, m.weight[r]);
        m.bias[r] = heads[rows.bias[r]];
    }
}

// Batch of points, feature-major (the layout HashGrid::encode_batch writes with stride kBatch).
struct BatchFeatures {
    alignas(32) float value[kMaxFeatures][kBatch];
};

// Pre-activations or their gradients for a batch, output-major.
struct BatchOutputs {
    alignas(32) float value[TextureField::kOutputs][kBatch];
};

// z = W e + b for a batch, 8 points per AVX2 instruction; each point's sum runs in feature order.
TDF_MULTIVERSION
void heads_forward(const HeadMatrix& m, const BatchFeatures& e, int features, std::size_t count,
                   BatchOutputs& z) {
    for (int r = 0; r < TextureField::kOutputs; ++r) {
        float* zr = z.value[r];
        for (std::size_t i = 0; i < count; ++i) zr[i] = 0.0f;
        if (r >= m.rows) continue;
        for (int k = 0; k < features; ++k) {
            const float w = m.weight[r][k];
            const float* ek = e.value[k];
            for (std::size_t i = 0; i < count; ++i) zr[i] += w * ek[i];
        }
        for (std::size_t i = 0; i < count; ++i) zr[i] += m.bias[r];
    }
}

inline void activate(const BatchOutputs& z, std::size_t i, FieldOutputs& out) {
    out.albedo = {sigmoid(z.value[0][i]), sigmoid(z.value[1][i]), sigmoid(z.value[2][i])};
    const Vec3f u(std::tanh(z.value[3][i]), std::tanh(z.value[4][i]), std::tanh(z.value[5][i]) + 1.0f);
    out.normal = normalize_or_zero(u, kNormalEps);
    out.label[0] = z.value[6][i];
    out.label[1] = z.value[7][i];
}

// dL/dz of point i from dL/d(outputs) (the activations' backward).
inline void activation_backward(const BatchOutputs& z, std::size_t i, const FieldOutputGrads& g, bool labels,
                                BatchOutputs& dz) {
    for (int k = 0; k < 3; ++k) {
        const float a = sigmoid(z.value[k][i]);
        dz.value[k][i] = g.d_albedo[k] * a * (1.0f - a);
    }
    // n = u / max(|u|, eps) with u = tanh(z) + (0,0,1): dn/du = (I - n n^T) / |u| above eps.
    const float t[3] = {std::tanh(z.value[3][i]), std::tanh(z.value[4][i]), std::tanh(z.value[5][i])};
    const Vec3f u(t[0], t[1], t[2] + 1.0f);
    const float len = length(u);
    Vec3f du;
    if (len > kNormalEps) {
        const Vec3f n = u / len;
        du = (g.d_normal - n * dot(n, g.d_normal)) / len;
    } else {
        du = g.d_normal / kNormalEps;
    }
    for (int k = 0; k < 3; ++k) dz.value[3 + k][i] = du[k] * (1.0f - t[k] * t[k]);
    dz.value[6][i] = labels ? g.d_label[0] : 0.0f;
    dz.value[7][i] = labels ? g.d_label[1] : 0.0f;
}

// Head gradients of a batch added to `partial` (flat head layout): dW[r][k] += sum_i dz[r][i]
// e[k][i], db[r] += sum_i dz[r][i]. The sums over the batch run in 8 interleaved lanes that
// are combined in a fixed order, so they vectorize and stay deterministic. Entries i >= count
// of dz must be 0 up to the next multiple of 8 (and e finite there).
TDF_MULTIVERSION
void heads_backward_weights(const HeadMatrix& m, const HeadRows& rows, const BatchFeatures& e,
                            const BatchOutputs& dz, int features, std::size_t count, float* partial) {
    const std::size_t padded = (count + 7) / 8 * 8;
    auto lane_sum = [](const float* lanes) {
        return ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) +
               ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
    };
    for (int r = 0; r < m.rows; ++r) {
        const float* d = dz.value[r];
        float* gw = partial + rows.weight[r];
        for (int k = 0; k < features; ++k) {
            const float* ek = e.value[k];
            float lanes[8] = {};
            for (std::size_t i = 0; i < padded; i += 8)
                for (int j = 0; j < 8; ++j) lanes[j] += d[i + std::size_t(j)] * ek[i + std::size_t(j)];
            gw[k] += lane_sum(lanes);
        }
        float lanes[8] = {};
        for (std::size_t i = 0; i < padded; i += 8)
            for (int j = 0; j < 8; ++j) lanes[j] += d[i + std::size_t(j)];
        partial[rows.bias[r]] += lane_sum(lanes);
    }
}

// de = W^T dz for a batch, written over `e` (feature-major, no longer needed).
TDF_MULTIVERSION
void heads_backward_features(const HeadMatrix& m, const BatchOutputs& dz, int features, std::size_t count,
                             BatchFeatures& e) {
    for (int k = 0; k < features; ++k) {
        float* de = e.value[k];
        for (std::size_t i = 0; i < count; ++i) de[i] = 0.0f;
        for (int r = 0; r < m.rows; ++r) {
            const float w = m.weight[r][k];
            const float* d = dz.value[r];
            for (std::size_t i = 0; i < count; ++i) de[i] += w * d[i];
        }
    }
}

}  // namespace

void TextureField::evaluate(const Vec3f* points, std::size_t n, FieldOutputs* out) const {
    const int features = feature_count();
    HeadMatrix heads;
    build_head_matrix(m_parameters.data() + m_head_offset, features, m_config.labels, heads);
    parallel_for(n, kChunk, [&](std::size_t begin, std::size_t end) {
        Vec3f x[kBatch];
        BatchFeatures e;
        BatchOutputs z;
        for (std::size_t b = begin; b < end; b += kBatch) {
            const std::size_t count = std::min(kBatch, end - b);
            for (std::size_t i = 0; i < count; ++i) x[i] = to_grid(points[b + i]);
            m_grid.encode_batch(m_parameters.data(), x, count, e.value[0], kBatch);
            heads_forward(heads, e, features, count, z);
            for (std::size_t i = 0; i < count; ++i) activate(z, i, out[b + i]);
        }
    });
}

void TextureField::backward(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                            std::vector<float>& gradient) const {
    if (gradient.size() != m_parameters.size()) gradient.assign(m_parameters.size(), 0.0f);
    if (n == 0) return;
    const int features = feature_count();
    const std::size_t levels = std::size_t(m_grid.level_count());
    const std::size_t head_count = m_parameters.size() - m_head_offset;
    const std::size_t chunks = chunk_count(n, kChunk);
    const std::size_t block_points = kBlockChunks * kChunk;
    HeadMatrix heads;
    build_head_matrix(m_parameters.data() + m_head_offset, features, m_config.labels, heads);
    const HeadRows rows = head_rows_of(features);

    // Scratch grows once and is reused by later calls (the hot path allocates nothing).
    if (m_scratch.head_partials.size() < chunks * head_count)
        m_scratch.head_partials.resize(chunks * head_count);
    if (m_scratch.d_features.size() < block_points * std::size_t(features))
        m_scratch.d_features.resize(block_points * std::size_t(features));
    float* d_features = m_scratch.d_features.data();
    float* partials = m_scratch.head_partials.data();

    // Two phases per block of points. Phase A (parallel over fixed chunks): forward, output
    // gradients -> head pre-activation gradients dz, per-chunk head gradients, and the encoding
    // gradient de = W^T dz stored level-major. Phase B (parallel over levels): each level's task
    // scatters de into its own table in point order. Every grid entry is therefore summed in
    // point order by exactly one task, and head gradients in chunk order: bit-identical for
    // any thread count, without atomics or per-thread copies of the 3.8 MB grid gradient, and
    // each task's scatter target (one level table, <= 256 KiB) stays in cache.
    for (std::size_t block_begin = 0; block_begin < n; block_begin += block_points) {
        const std::size_t block_end = std::min(n, block_begin + block_points);
        const std::size_t first_chunk = block_begin / kChunk;
        const std::size_t block_chunks = chunk_count(block_end - block_begin, kChunk);

        parallel_for(block_chunks, 1, [&](std::size_t c0, std::size_t c1) {
            Vec3f x[kBatch];
            BatchFeatures e;
            BatchOutputs z, dz;
            // Padding entries of a short batch must be finite zeros for the lane sums.
            for (auto& row : e.value) std::fill(row, row + kBatch, 0.0f);
            for (auto& row : dz.value) std::fill(row, row + kBatch, 0.0f);
            for (std::size_t c = c0; c < c1; ++c) {
                float* partial = partials + (first_chunk + c) * head_count;
                std::fill(partial, partial + head_count, 0.0f);
                const std::size_t begin = block_begin + c * kChunk;
                const std::size_t end = std::min(block_end, begin + kChunk);
                for (std::size_t b = begin; b < end; b += kBatch) {
                    const std::size_t count = std::min(kBatch, end - b);
                    for (std::size_t i = 0; i < count; ++i) x[i] = to_grid(points[b + i]);
                    m_grid.encode_batch(m_parameters.data(), x, count, e.value[0], kBatch);
                    heads_forward(heads, e, features, count, z);
                    for (std::size_t i = 0; i < count; ++i)
                        activation_backward(z, i, grads[b + i], m_config.labels, dz);
                    for (std::size_t i = count; i < kBatch; ++i)
                        for (auto& row : dz.value) row[i] = 0.0f;
                    heads_backward_weights(heads, rows, e, dz, features, count, partial);
                    heads_backward_features(heads, dz, features, count, e);
                    const std::size_t local = b - block_begin;
                    for (std::size_t l = 0; l < levels; ++l) {
                        float* dst = d_features + (l * block_points + local) * 2;
                        const float* d0 = e.value[2 * l];
                        const float* d1 = e.value[2 * l + 1];
                        for (std::size_t i = 0; i < count; ++i) {
                            dst[2 * i] = d0[i];
                            dst[2 * i + 1] = d1[i];
                        }
                    }
                }
            }
        });

        parallel_for(levels, 1, [&](std::size_t l0, std::size_t l1) {
            Vec3f x[kBatch];
            for (std::size_t l = l0; l < l1; ++l) {
                const float* src = d_features + l * block_points * 2;
                for (std::size_t b = block_begin; b < block_end; b += kBatch) {
                    const std::size_t count = std::min(kBatch, block_end - b);
                    for (std::size_t i = 0; i < count; ++i) x[i] = to_grid(points[b + i]);
                    m_grid.accumulate_level_gradient_batch(
                        int(l), x, count, src + (b - block_begin) * 2, gradient.data());
                }
            }
        });
    }

    // Head gradients: per-chunk partials summed in chunk order (in double, then added once).
    float* head_gradient = gradient.data() + m_head_offset;
    parallel_for(head_count, 64, [&](std::size_t j0, std::size_t j1) {
        for (std::size_t j = j0; j < j1; ++j) {
            double sum = 0;
            for (std::size_t c = 0; c < chunks; ++c) sum += double(partials[c * head_count + j]);
            head_gradient[j] += float(sum);
        }
    });
}

}  // namespace tdf
