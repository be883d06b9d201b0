#include <tdf/train/part_label_head.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

// Points per fixed block: encoded together level by level (HashGrid::encode_levels, the field's
// fast path), and partial sums are per block, combined in block order, so the result does not
// depend on the thread count.
constexpr std::size_t kBlock = 2048;

// Calls body(first, count, e) for every block of `n` points in parallel, `e` holding the
// block's encodings feature-major (feature k of point first + i at e[k * kBlock + i]). `coords`
// (3 x n, optional) receives the sanitised grid coordinates, structure-of-arrays.
template <typename Body>
void for_each_encoded_block(const TextureField& field, const Vec3f* points, std::size_t n, float* coords,
                            Body&& body) {
    const std::size_t features = std::size_t(field.feature_count());
    parallel_for(chunk_count(n, kBlock), 1, [&](std::size_t b0, std::size_t b1) {
        std::vector<float> local(3 * kBlock), e(features * kBlock);
        for (std::size_t block = b0; block < b1; ++block) {
            const std::size_t first = block * kBlock, count = std::min(kBlock, n - first);
            for (std::size_t i = 0; i < count; ++i) {
                const Vec3f g = field.to_grid(points[first + i]);
                for (std::size_t d = 0; d < 3; ++d) {
                    local[d * kBlock + i] = HashGrid::sanitize_coordinate(g[int(d)]);
                    if (coords) coords[d * n + first + i] = local[d * kBlock + i];
                }
            }
            const GridPointArrays x{{local.data(), local.data() + kBlock, local.data() + 2 * kBlock}};
            field.grid().encode_levels(field.parameters().data(), x, count, e.data(), kBlock);
            body(first, count, e.data());
        }
    });
}

// z = W e + b for point i of a feature-major block.
void head_forward(const float* w, int parts, int features, const float* e, std::size_t i, float* z) {
    const float* b = w + std::size_t(parts) * std::size_t(features);
    for (int c = 0; c < parts; ++c) {
        const float* row = w + std::size_t(c) * std::size_t(features);
        float s = 0;
        for (int k = 0; k < features; ++k) s += row[k] * e[std::size_t(k) * kBlock + i];
        z[c] = s + b[c];
    }
}

}  // namespace

double softmax_cross_entropy(const float* logits, int count, int label, float scale, float* d_logits) {
    TDF_CHECK(count >= 1 && label >= 0 && label < count);
    const float m = *std::max_element(logits, logits + count);
    double sum = 0;
    for (int c = 0; c < count; ++c) sum += std::exp(double(logits[c] - m));
    if (d_logits)
        for (int c = 0; c < count; ++c) {
            const double p = std::exp(double(logits[c] - m)) / sum;
            d_logits[c] = scale * float(p - (c == label ? 1.0 : 0.0));
        }
    return double(m - logits[label]) + std::log(sum);
}

PartLabelHead::PartLabelHead(int parts, int features, std::uint64_t seed) : m_parts(parts), m_features(features) {
    if (parts < 1) throw_error("part label head: {} parts (at least 1)", parts);
    TDF_CHECK(features >= 1);
    m_parameters.resize(std::size_t(parts) * std::size_t(features + 1));
    Rng rng(seed ^ 0x6c6162656cULL);  // "label": a stream of its own, not the field's
    const float bound = 1.0f / std::sqrt(float(features));
    for (float& p : m_parameters) p = rng.uniform(-bound, bound);
}

void PartLabelHead::logits(const TextureField& field, const Vec3f* points, std::size_t n,
                           std::vector<float>& out) const {
    TDF_CHECK(field.feature_count() == m_features);
    out.resize(n * std::size_t(m_parts));
    for_each_encoded_block(field, points, n, nullptr, [&](std::size_t first, std::size_t count, const float* e) {
        for (std::size_t i = 0; i < count; ++i)
            head_forward(m_parameters.data(), m_parts, m_features, e, i, out.data() + (first + i) * std::size_t(m_parts));
    });
}

std::vector<int> PartLabelHead::predict(const TextureField& field, const Vec3f* points, std::size_t n) const {
    std::vector<float> z;
    logits(field, points, n, z);
    std::vector<int> parts(n);
    for (std::size_t i = 0; i < n; ++i) {
        const float* zi = z.data() + i * std::size_t(m_parts);
        parts[i] = int(std::max_element(zi, zi + m_parts) - zi);
    }
    return parts;
}

double PartLabelHead::loss_and_gradient(const TextureField& field, const Vec3f* points, const int* labels,
                                        std::size_t n, float weight, std::vector<float>& head_gradient,
                                        std::vector<float>* field_gradient, std::size_t* labelled_out) const {
    TDF_CHECK(field.feature_count() == m_features);
    const std::size_t parts = std::size_t(m_parts), features = std::size_t(m_features);
    const std::size_t head_count = m_parameters.size();
    if (head_gradient.size() != head_count) head_gradient.assign(head_count, 0.0f);
    if (field_gradient) TDF_CHECK(field_gradient->size() == field.parameter_count());
    std::size_t labelled = 0;
    for (std::size_t i = 0; i < n; ++i) {
        TDF_CHECK(labels[i] < m_parts);
        labelled += labels[i] >= 0;
    }
    if (labelled_out) *labelled_out = labelled;
    if (labelled == 0) return 0.0;
    const float scale = weight / float(labelled);

    // dL/d(encoding), feature-major (feature k of point i at k * n + i): the layout the grid's
    // per-level scatter reads; and the grid coordinates it needs.
    std::vector<float> d_e(field_gradient ? features * n : 0, 0.0f);
    std::vector<float> coords(field_gradient ? 3 * n : 0);
    const std::size_t blocks = chunk_count(n, kBlock);
    std::vector<double> loss_partial(blocks, 0.0);
    std::vector<float> head_partial(blocks * head_count, 0.0f);
    const float* w = m_parameters.data();
    for_each_encoded_block(field, points, n, field_gradient ? coords.data() : nullptr,
                           [&](std::size_t first, std::size_t count, const float* e) {
        float* gw = head_partial.data() + first / kBlock * head_count;
        float* gb = gw + parts * features;
        std::vector<float> z(parts), dz(parts);
        double loss = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const int label = labels[first + i];
            if (label < 0) continue;
            head_forward(w, m_parts, m_features, e, i, z.data());
            loss += softmax_cross_entropy(z.data(), m_parts, label, scale, dz.data());
            for (std::size_t r = 0; r < parts; ++r) {
                for (std::size_t k = 0; k < features; ++k) gw[r * features + k] += dz[r] * e[k * kBlock + i];
                gb[r] += dz[r];
            }
            if (field_gradient)
                for (std::size_t k = 0; k < features; ++k) {
                    float s = 0;
                    for (std::size_t r = 0; r < parts; ++r) s += w[r * features + k] * dz[r];
                    d_e[k * n + first + i] = s;
                }
        }
        loss_partial[first / kBlock] = loss;
    });
    double loss = 0;
    for (double l : loss_partial) loss += l;
    parallel_for(head_count, 64, [&](std::size_t j0, std::size_t j1) {
        for (std::size_t j = j0; j < j1; ++j) {
            double sum = 0;
            for (std::size_t c = 0; c < blocks; ++c) sum += double(head_partial[c * head_count + j]);
            head_gradient[j] += float(sum);
        }
    });
    if (field_gradient) {
        // The grid's share: each level's entries are summed in point order by one task.
        const GridPointArrays x{{coords.data(), coords.data() + n, coords.data() + 2 * n}};
        const HashGrid& grid = field.grid();
        parallel_for(std::size_t(grid.level_count()), 1, [&](std::size_t l0, std::size_t l1) {
            for (std::size_t l = l0; l < l1; ++l)
                grid.accumulate_level_gradient(int(l), x, n, d_e.data() + 2 * l * n, d_e.data() + (2 * l + 1) * n,
                                               field_gradient->data());
        });
    }
    return double(weight) * loss / double(labelled);
}

}  // namespace tdf
