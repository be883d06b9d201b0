#include <tdf/field/hash_grid.h>

#include <tdf/core/error.h>

#include <cmath>

namespace tdf {

HashGrid::HashGrid(const HashGridConfig& config) : m_config(config) {
    if (config.levels < 1 || config.levels > kMaxLevels)
        throw_error("field.levels: {} is out of range 1..{}", config.levels, kMaxLevels);
    if (config.log2_table_size < 4 || config.log2_table_size > 24)
        throw_error("field.log2_table_size: {} is out of range 4..24", config.log2_table_size);
    if (config.base_resolution < 2)
        throw_error("field.base_resolution: {} must be at least 2", config.base_resolution);
    if (!(config.per_level_scale >= 1.0f) || !std::isfinite(config.per_level_scale))
        throw_error("field.per_level_scale: {} must be a finite value >= 1", config.per_level_scale);

    const std::uint64_t max_entries = std::uint64_t(1) << config.log2_table_size;
    const float log2_scale = std::log2(config.per_level_scale);
    std::uint64_t offset = 0;
    for (int level = 0; level < config.levels; ++level) {
        HashGridLevel l;
        // Matches reference: float32 exp2f(level * log2(scale)) * base - 1, res = ceil + 1
        // (tcnn `grid_scale` / `grid_resolution`, spec 4.2). The float rounding decides
        // res_1 = 24 (not 25) for the defaults; a test pins the table.
        l.scale = std::exp2(float(level) * log2_scale) * float(config.base_resolution) - 1.0f;
        if (!(l.scale < 1.6e6f))  // res^2 must fit the uint32 stride arithmetic of dense levels
            throw_error("field: level {} scale {} is too fine (reduce levels or per_level_scale)", level,
                        l.scale);
        l.resolution = std::uint32_t(std::ceil(l.scale)) + 1u;
        const std::uint64_t dense = std::uint64_t(l.resolution) * l.resolution * l.resolution;
        const std::uint64_t entries = std::min(dense, max_entries);
        l.table_size = std::uint32_t((entries + 7) / 8 * 8);
        // tcnn hashes a level when the dense stride exceeds the table (grid_index).
        l.hashed = dense > l.table_size;
        l.offset = std::uint32_t(offset);
        l.modulo_magic = ~std::uint64_t(0) / l.table_size + 1;
        TDF_CHECK(!l.hashed || (l.table_size & (l.table_size - 1)) == 0);
        offset += l.table_size;
        m_levels.push_back(l);
    }
    m_entry_count = std::size_t(offset);
}

void HashGrid::encode_batch(const float* grid_params, const Vec3f* x, std::size_t count, float* features) const {
    TDF_CHECK_LE(count, kBatch);
    GridCorners c[kBatch];
    const std::size_t stride = std::size_t(feature_count());
    for (int level = 0; level < level_count(); ++level) {
        const float* table = grid_params + std::size_t(m_levels[std::size_t(level)].offset) * kFeaturesPerLevel;
        for (std::size_t i = 0; i < count; ++i) {
            corners(level, x[i], c[i]);
            for (int k = 0; k < 8; ++k) __builtin_prefetch(table + std::size_t(c[i].index[k]) * kFeaturesPerLevel);
        }
        for (std::size_t i = 0; i < count; ++i) {
            float f0 = 0, f1 = 0;
            for (int k = 0; k < 8; ++k) {
                const float* entry = table + std::size_t(c[i].index[k]) * kFeaturesPerLevel;
                f0 += c[i].weight[k] * entry[0];
                f1 += c[i].weight[k] * entry[1];
            }
            features[i * stride + std::size_t(2 * level)] = f0;
            features[i * stride + std::size_t(2 * level) + 1] = f1;
        }
    }
}

void HashGrid::accumulate_level_gradient_batch(int level, const Vec3f* x, std::size_t count,
                                               const float* d_features, float* grid_gradient) const {
    TDF_CHECK_LE(count, kBatch);
    GridCorners c[kBatch];
    float* table = grid_gradient + std::size_t(m_levels[std::size_t(level)].offset) * kFeaturesPerLevel;
    for (std::size_t i = 0; i < count; ++i) {
        if (d_features[2 * i] == 0.0f && d_features[2 * i + 1] == 0.0f) continue;
        corners(level, x[i], c[i]);
        for (int k = 0; k < 8; ++k) __builtin_prefetch(table + std::size_t(c[i].index[k]) * kFeaturesPerLevel, 1);
    }
    for (std::size_t i = 0; i < count; ++i) {
        const float d0 = d_features[2 * i], d1 = d_features[2 * i + 1];
        if (d0 == 0.0f && d1 == 0.0f) continue;
        for (int k = 0; k < 8; ++k) {
            float* entry = table + std::size_t(c[i].index[k]) * kFeaturesPerLevel;
            entry[0] += c[i].weight[k] * d0;
            entry[1] += c[i].weight[k] * d1;
        }
    }
}

}  // namespace tdf
