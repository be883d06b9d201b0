#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/release.h>
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>

#include <cmath>
#include <cstring>

#include "multiversion_impl.h"

namespace tdf {

namespace {

// Points per backward block: the feature-major dL/d(encoding) of one block is 32768 x 32 floats
// (4 MiB), small enough to stay cache-friendly, large enough that the per-level scatter
// tasks amortize their start.
constexpr std::size_t kBlockChunks = 32;

// Points encoded level by level in one go (HashGrid::encode_levels), a whole number of chunks:
// each level's table is read by 2048 points in a row, and the block's encodings (256 KiB) are
// still in L2 when the heads read them (8192 points made the heads 5x slower: L2 misses).
constexpr std::size_t kEncodeBlock = 2 * TextureField::kChunk;

// Row stride of feature-major block buffers: one cache line more than the rows, so the 32
// feature rows that a batch reads or writes together do not all map to the same L1 cache set
// (power-of-two strides made them evict each other).
constexpr std::size_t padded_stride(std::size_t points) { return points + 16; }
constexpr std::size_t kEncodeStride = padded_stride(kEncodeBlock);

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

// 8 floats as one value (GCC vector extension): elementwise arithmetic, compiled to one AVX2
// instruction or two SSE ones, so every lane does the same operations as scalar code.
typedef float Float8 __attribute__((vector_size(32)));

// Pre-activations or their gradients for a batch, output-major.
struct BatchOutputs {
    alignas(32) float value[TextureField::kOutputs][kBatch];
};

// Feature-major encodings (or their gradients) of a block of points: feature k of point i at
// `data[k * stride + i]`. T = const float for read-only use.
template <typename T>
struct FeatureRows {
    T* data;
    std::size_t stride;
    T* feature(int k, std::size_t first) const { return data + std::size_t(k) * stride + first; }
};
using BlockFeatures = FeatureRows<float>;
using ConstBlockFeatures = FeatureRows<const float>;

// z = W e + b for `count` <= kBatch points starting at `first`, 8 points at a time with the
// sums of all rows in registers (each point's sum runs in feature order, then the bias). Reads
// the features up to the next multiple of 8 (finite padding); rows >= m.rows come out 0.
TDF_MULTIVERSION
void heads_forward(const HeadMatrix& m, const ConstBlockFeatures& e, std::size_t first, int features,
                   std::size_t count, BatchOutputs& z) {
    constexpr int kRows = TextureField::kOutputs;
    for (std::size_t i = 0; i < count; i += 8) {
        Float8 acc[kRows] = {};
        for (int k = 0; k < features; ++k) {
            Float8 ek;
            std::memcpy(&ek, e.feature(k, first + i), sizeof ek);
            for (int r = 0; r < kRows; ++r) acc[r] += m.weight[r][k] * ek;
        }
        for (int r = 0; r < kRows; ++r) {
            const Float8 zr = r < m.rows ? acc[r] + m.bias[r] : Float8{};
            std::memcpy(z.value[r] + i, &zr, sizeof zr);
        }
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
void heads_backward_weights(const HeadMatrix& m, const HeadRows& rows, const ConstBlockFeatures& e,
                            std::size_t first, const BatchOutputs& dz, int features, std::size_t count,
                            float* partial) {
    const std::size_t padded = (count + 7) / 8 * 8;
    auto lane_sum = [](const float* lanes) {
        return ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) +
               ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
    };
    for (int r = 0; r < m.rows; ++r) {
        const float* d = dz.value[r];
        float* gw = partial + rows.weight[r];
        for (int k = 0; k < features; ++k) {
            const float* ek = e.feature(k, first);
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

// de = W^T dz for a batch, written to `d_features` from point `first` on (feature-major), 8
// points at a time with dz in registers; each sum runs in row order. Writes up to the next
// multiple of 8 (dz is 0 there). Rows >= m.rows have zero weights and zero dz.
TDF_MULTIVERSION
void heads_backward_features(const HeadMatrix& m, const BatchOutputs& dz, int features, std::size_t count,
                             const BlockFeatures& d_features, std::size_t first) {
    constexpr int kRows = TextureField::kOutputs;
    for (std::size_t i = 0; i < count; i += 8) {
        Float8 d[kRows];
        for (int r = 0; r < kRows; ++r) std::memcpy(&d[r], dz.value[r] + i, sizeof d[r]);
        for (int k = 0; k < features; ++k) {
            Float8 de = {};
            for (int r = 0; r < kRows; ++r) de += m.weight[r][k] * d[r];
            std::memcpy(d_features.feature(k, first + i), &de, sizeof de);
        }
    }
}

// Per-thread scratch of the parallel tasks: grid coordinates and encodings of one encode block.
// Grows on first use and is reused afterwards, so the hot path allocates nothing.
struct TaskScratch {
    std::vector<float> coords;    // 3 x kEncodeStride
    std::vector<float> features;  // kMaxFeatures x kEncodeStride, zero-initialized (finite padding)
};

TaskScratch& task_scratch() {
    thread_local TaskScratch scratch;
    if (scratch.features.empty()) {
        scratch.coords.resize(3 * kEncodeStride);
        scratch.features.resize(std::size_t(kMaxFeatures) * kEncodeStride);
    }
    return scratch;
}

// Sanitized grid coordinates of `count` world points, written structure-of-arrays to
// coords[d * stride + i].
GridPointArrays to_grid_arrays(const TextureField& field, const Vec3f* points, std::size_t count,
                               float* coords, std::size_t stride) {
    for (std::size_t i = 0; i < count; ++i) {
        const Vec3f g = field.to_grid(points[i]);
        for (int d = 0; d < 3; ++d) coords[std::size_t(d) * stride + i] = HashGrid::sanitize_coordinate(g[d]);
    }
    return GridPointArrays{{coords, coords + stride, coords + 2 * stride}};
}

// Encodes one encode block into `e` and zeroes the rows from `count` to the next multiple of 8:
// the heads read those padding entries 8 points at a time, and they must be finite.
void encode_block(const HashGrid& grid, const float* parameters, const GridPointArrays& x, std::size_t count,
                  int features, const BlockFeatures& e) {
    grid.encode_levels(parameters, x, count, e.data, e.stride);
    const std::size_t padded = (count + 7) / 8 * 8;
    for (int k = 0; k < features; ++k) std::fill(e.feature(k, count), e.feature(k, padded), 0.0f);
}

// Floats of the cached encodings of `n` points: whole encode blocks of padded rows.
std::size_t cache_floats(std::size_t n, int features) {
    return chunk_count(n, kEncodeBlock) * std::size_t(features) * kEncodeStride;
}

}  // namespace

void FieldCache::clear() {
    release(m_features);
    m_points = 0;
    m_field = nullptr;
}

void TextureField::evaluate(const Vec3f* points, std::size_t n, FieldOutputs* out) const {
    evaluate_impl(points, n, out, nullptr);
}

void TextureField::evaluate(const Vec3f* points, std::size_t n, FieldOutputs* out, FieldCache& cache) const {
    const std::size_t floats = cache_floats(n, feature_count());
    if (cache.m_features.size() < floats) cache.m_features.resize(floats);
    cache.m_points = n;
    cache.m_field = this;
    evaluate_impl(points, n, out, cache.m_features.data());
}

void TextureField::evaluate_impl(const Vec3f* points, std::size_t n, FieldOutputs* out, float* cache) const {
    const int features = feature_count();
    HeadMatrix heads;
    build_head_matrix(m_parameters.data() + m_head_offset, features, m_config.labels, heads);
    // Fixed encode blocks (not TBB's ranges), so a block's cached encodings sit at a known place.
    parallel_for(chunk_count(n, kEncodeBlock), 1, [&](std::size_t s0, std::size_t s1) {
        TaskScratch& scratch = task_scratch();
        BatchOutputs z;
        for (std::size_t s = s0; s < s1; ++s) {
            const std::size_t block = s * kEncodeBlock;
            const std::size_t count = std::min(kEncodeBlock, n - block);
            const GridPointArrays x =
                to_grid_arrays(*this, points + block, count, scratch.coords.data(), kEncodeStride);
            const BlockFeatures e{
                cache ? cache + s * std::size_t(features) * kEncodeStride : scratch.features.data(),
                kEncodeStride};
            encode_block(m_grid, m_parameters.data(), x, count, features, e);
            for (std::size_t b = 0; b < count; b += kBatch) {
                const std::size_t batch = std::min(kBatch, count - b);
                heads_forward(heads, ConstBlockFeatures{e.data, e.stride}, b, features, batch, z);
                for (std::size_t i = 0; i < batch; ++i) activate(z, i, out[block + b + i]);
            }
        }
    });
}

void TextureField::backward(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                            std::vector<float>& gradient) const {
    backward_impl(points, grads, n, gradient, nullptr);
}

void TextureField::backward(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                            std::vector<float>& gradient, const FieldCache& cache) const {
    if (cache.m_field != this || cache.m_points != n)
        throw_error(
            "field backward: the cache holds {} points of {} field, not the {} points of this "
            "backward (fill it with evaluate() on the same points first)",
            cache.m_points,
            cache.m_field == this ? "this" : "another",
            n);
    backward_impl(points, grads, n, gradient, cache.m_features.data());
}

void TextureField::backward_impl(const Vec3f* points, const FieldOutputGrads* grads, std::size_t n,
                                 std::vector<float>& gradient, const float* cache) const {
    if (gradient.size() != m_parameters.size()) gradient.assign(m_parameters.size(), 0.0f);
    if (n == 0) return;
    const int features = feature_count();
    const std::size_t levels = std::size_t(m_grid.level_count());
    const std::size_t head_count = m_parameters.size() - m_head_offset;
    const std::size_t chunks = chunk_count(n, kChunk);
    const std::size_t block_points = kBlockChunks * kChunk;
    const std::size_t block_stride = padded_stride(block_points);
    HeadMatrix heads;
    build_head_matrix(m_parameters.data() + m_head_offset, features, m_config.labels, heads);
    const HeadRows rows = head_rows_of(features);

    // Scratch grows once and is reused by later calls (the hot path allocates nothing).
    if (m_scratch.head_partials.size() < chunks * head_count)
        m_scratch.head_partials.resize(chunks * head_count);
    if (m_scratch.d_features.size() < block_stride * std::size_t(features))
        m_scratch.d_features.resize(block_stride * std::size_t(features));
    if (m_scratch.coords.size() < block_stride * 3) m_scratch.coords.resize(block_stride * 3);
    BlockFeatures d_features{m_scratch.d_features.data(), block_stride};
    float* coords = m_scratch.coords.data();
    float* partials = m_scratch.head_partials.data();

    // Two phases per block of points. Phase A (parallel over fixed encode blocks of whole
    // chunks): grid coordinates, forward, output gradients -> head pre-activation gradients dz,
    // per-chunk head gradients, and the encoding gradient de = W^T dz, stored feature-major.
    // Phase B (parallel over levels): each level's task scatters de into its own table in point
    // order. Every grid entry is therefore summed in point order by exactly one task, and head
    // gradients in chunk order: bit-identical for any thread count, without atomics or
    // per-thread copies of the 3.8 MB grid gradient, and each task's scatter target (one level
    // table, <= 256 KiB) stays in cache.
    for (std::size_t block_begin = 0; block_begin < n; block_begin += block_points) {
        const std::size_t block_end = std::min(n, block_begin + block_points);
        const std::size_t block_count = block_end - block_begin;
        const GridPointArrays block_x{{coords, coords + block_stride, coords + 2 * block_stride}};

        parallel_for(chunk_count(block_count, kEncodeBlock), 1, [&](std::size_t s0, std::size_t s1) {
            TaskScratch& scratch = task_scratch();
            BatchOutputs z, dz;
            // Padding entries of a short batch must be finite zeros for the lane sums.
            for (auto& row : dz.value) std::fill(row, row + kBatch, 0.0f);
            for (std::size_t s = s0; s < s1; ++s) {
                const std::size_t local = s * kEncodeBlock;  // first point, relative to the block
                const std::size_t count = std::min(kEncodeBlock, block_count - local);
                const GridPointArrays x =
                    to_grid_arrays(*this, points + block_begin + local, count, coords + local, block_stride);
                ConstBlockFeatures e{scratch.features.data(), kEncodeStride};
                if (cache) {
                    const std::size_t cached_block = (block_begin + local) / kEncodeBlock;
                    e.data = cache + cached_block * std::size_t(features) * kEncodeStride;
                } else {
                    encode_block(m_grid,
                                 m_parameters.data(),
                                 x,
                                 count,
                                 features,
                                 BlockFeatures{scratch.features.data(), kEncodeStride});
                }
                for (std::size_t c = 0; c < chunk_count(count, kChunk); ++c) {
                    float* partial = partials + ((block_begin + local) / kChunk + c) * head_count;
                    std::fill(partial, partial + head_count, 0.0f);
                    const std::size_t chunk_end = std::min(count, (c + 1) * kChunk);
                    for (std::size_t b = c * kChunk; b < chunk_end; b += kBatch) {
                        const std::size_t batch = std::min(kBatch, chunk_end - b);
                        const std::size_t first = block_begin + local + b;  // global point index
                        heads_forward(heads, e, b, features, batch, z);
                        for (std::size_t i = 0; i < batch; ++i)
                            activation_backward(z, i, grads[first + i], m_config.labels, dz);
                        for (std::size_t i = batch; i < kBatch; ++i)
                            for (auto& row : dz.value) row[i] = 0.0f;
                        heads_backward_weights(heads, rows, e, b, dz, features, batch, partial);
                        heads_backward_features(heads, dz, features, batch, d_features, local + b);
                    }
                }
            }
        });

        parallel_for(levels, 1, [&](std::size_t l0, std::size_t l1) {
            for (std::size_t l = l0; l < l1; ++l)
                m_grid.accumulate_level_gradient(int(l),
                                                 block_x,
                                                 block_count,
                                                 d_features.feature(int(2 * l), 0),
                                                 d_features.feature(int(2 * l + 1), 0),
                                                 gradient.data());
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
