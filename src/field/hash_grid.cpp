#include <tdf/core/error.h>
#include <tdf/field/hash_grid.h>

#include <cmath>

#include "multiversion_impl.h"

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
    static_assert(kMaxCoordinate * 2.0e6f < 2.1e9f, "cell indices must fit an int");

    const std::uint64_t max_entries = std::uint64_t(1) << config.log2_table_size;
    const float log2_scale = std::log2(config.per_level_scale);
    std::uint64_t offset = 0;
    for (int level = 0; level < config.levels; ++level) {
        HashGridLevel l;
        // Matches reference: float32 exp2f(level * log2(scale)) * base - 1, res = ceil + 1
        // (tcnn `grid_scale` / `grid_resolution`, spec 4.2). The float rounding decides
        // res_1 = 24 (not 25) for the defaults; a test pins the table.
        l.scale = std::exp2(float(level) * log2_scale) * float(config.base_resolution) - 1.0f;
        if (!(l.scale < 2.0e6f))  // keeps scale * kMaxCoordinate inside the int range
            throw_error(
                "field: level {} scale {} is too fine (reduce levels or per_level_scale)", level, l.scale);
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

namespace {

constexpr std::size_t kBatch = HashGrid::kBatch;

// One level's corners for a batch of points, structure-of-arrays.
struct BatchCorners {
    alignas(32) std::uint32_t index[8][kBatch];
    alignas(32) float weight[8][kBatch];
};

// Grid-space coordinates of a batch, structure-of-arrays.
struct BatchPoints {
    alignas(32) float coord[3][kBatch];
};

// The batch version of HashGrid::corners (same arithmetic, point by point identical).
TDF_MULTIVERSION
void batch_corners(const HashGridLevel& l, const GridPointArrays& p, std::size_t first, std::size_t count,
                   BatchCorners& out) {
    alignas(32) std::uint32_t g[3][kBatch];
    alignas(32) float w1[3][kBatch];
    for (int d = 0; d < 3; ++d) {
        for (std::size_t i = 0; i < count; ++i) {
            const float pos = l.scale * p.coord[d][first + i] + 0.5f;
            int cell = int(pos);
            cell -= int(pos < float(cell));
            g[d][i] = std::uint32_t(cell);
            w1[d][i] = pos - float(cell);
        }
    }
    if (l.hashed) {
        const std::uint32_t mask = l.table_size - 1u;
        alignas(32) std::uint32_t hy[kBatch], hz[kBatch];
        for (std::size_t i = 0; i < count; ++i) {
            hy[i] = g[1][i] * 2654435761u;
            hz[i] = g[2][i] * 805459861u;
        }
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t ox = std::uint32_t(c & 1);
            const std::uint32_t oy = (c >> 1) & 1 ? 2654435761u : 0u, oz = c >> 2 ? 805459861u : 0u;
            std::uint32_t* index = out.index[c];
            for (std::size_t i = 0; i < count; ++i)
                index[i] = ((g[0][i] + ox) ^ (hy[i] + oy) ^ (hz[i] + oz)) & mask;
        }
    } else {
        const std::uint32_t r = l.resolution, r2 = l.resolution * l.resolution, size = l.table_size;
        for (int c = 0; c < 8; ++c) {
            const std::uint32_t ox = std::uint32_t(c & 1), oy = std::uint32_t((c >> 1) & 1),
                                oz = std::uint32_t(c >> 2);
            std::uint32_t* index = out.index[c];
            std::uint32_t outside = 0;
            for (std::size_t i = 0; i < count; ++i) {
                index[i] = (g[0][i] + ox) + (g[1][i] + oy) * r + (g[2][i] + oz) * r2;
                outside |= std::uint32_t(index[i] >= size);
            }
            // The modulo only bites at the +0.5 boundary or for wrapped coordinates: a separate
            // scalar pass, only when needed, keeps the loop above vectorized.
            if (outside)
                for (std::size_t i = 0; i < count; ++i)
                    if (index[i] >= size) index[i] = detail::fast_mod(index[i], l.modulo_magic, size);
        }
    }
    for (int c = 0; c < 8; ++c) {
        const int bx = c & 1, by = (c >> 1) & 1, bz = c >> 2;
        for (std::size_t i = 0; i < count; ++i) {
            const float wx = bx ? w1[0][i] : 1.0f - w1[0][i];
            const float wy = by ? w1[1][i] : 1.0f - w1[1][i];
            const float wz = bz ? w1[2][i] : 1.0f - w1[2][i];
            out.weight[c][i] = wx * wy * wz;
        }
    }
}

TDF_MULTIVERSION
void gather_level(const HashGridLevel& l, const float* table, const BatchCorners& bc, std::size_t count,
                  float* f0, float* f1) {
    // Hashed tables (256 KiB each) do not fit L1 and, with other processes on the core, are not
    // reliably in L2 (measured: the prefetch still pays off level by level). Corners c and c+1
    // differ only in x, which the hash multiplies by 1: they nearly always share a cache line,
    // so prefetching the even corners covers the lines.
    if (l.hashed)
        for (int c = 0; c < 8; c += 2)
            for (std::size_t i = 0; i < count; ++i)
                __builtin_prefetch(table + std::size_t(bc.index[c][i]) * 2);
    for (std::size_t i = 0; i < count; ++i) {
        float a = 0, b = 0;
        for (int c = 0; c < 8; ++c) {
            const float* entry = table + std::size_t(bc.index[c][i]) * 2;
            a += bc.weight[c][i] * entry[0];
            b += bc.weight[c][i] * entry[1];
        }
        f0[i] = a;
        f1[i] = b;
    }
}

}  // namespace

void HashGrid::encode_batch(const float* grid_params, const Vec3f* x, std::size_t count, float* features,
                            std::size_t stride) const {
    TDF_CHECK_LE(count, kBatch);
    TDF_CHECK_LE(count, stride);
    BatchPoints p;
    for (std::size_t i = 0; i < count; ++i)
        for (int d = 0; d < 3; ++d) p.coord[d][i] = sanitize_coordinate(x[i][d]);
    encode_levels(
        grid_params, GridPointArrays{{p.coord[0], p.coord[1], p.coord[2]}}, count, features, stride);
}

void HashGrid::encode_levels(const float* grid_params, const GridPointArrays& x, std::size_t count,
                             float* features, std::size_t stride) const {
    TDF_CHECK_LE(count, stride);
    BatchCorners bc;
    for (int level = 0; level < level_count(); ++level) {
        const HashGridLevel& l = m_levels[std::size_t(level)];
        const float* table = grid_params + std::size_t(l.offset) * kFeaturesPerLevel;
        float* f0 = features + std::size_t(2 * level) * stride;
        float* f1 = features + std::size_t(2 * level + 1) * stride;
        for (std::size_t b = 0; b < count; b += kBatch) {
            const std::size_t n = std::min(kBatch, count - b);
            batch_corners(l, x, b, n, bc);
            gather_level(l, table, bc, n, f0 + b, f1 + b);
        }
    }
}

void HashGrid::accumulate_level_gradient(int level, const GridPointArrays& x, std::size_t count,
                                         const float* d0, const float* d1, float* grid_gradient) const {
    const HashGridLevel& l = m_levels[std::size_t(level)];
    float* table = grid_gradient + std::size_t(l.offset) * kFeaturesPerLevel;
    BatchCorners bc;
    for (std::size_t b = 0; b < count; b += kBatch) {
        const std::size_t n = std::min(kBatch, count - b);
        batch_corners(l, x, b, n, bc);
        // Scalar and in point order: corners of different points may share entries, and the
        // order of the additions must not depend on anything but the point order.
        for (std::size_t i = 0; i < n; ++i) {
            const float g0 = d0[b + i], g1 = d1[b + i];
            if (g0 == 0.0f && g1 == 0.0f) continue;
            for (int c = 0; c < 8; ++c) {
                float* entry = table + std::size_t(bc.index[c][i]) * kFeaturesPerLevel;
                entry[0] += bc.weight[c][i] * g0;
                entry[1] += bc.weight[c][i] * g1;
            }
        }
    }
}

}  // namespace tdf
