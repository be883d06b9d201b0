#pragma once
/// Multi-resolution hash-grid encoding (Mueller et al. 2022) with tiny-cuda-nn's exact level,
/// table-size and indexing rules (spec 4.2), hand-written on the CPU.
///
/// The grid maps a point x in grid coordinates (nominally [0,1]^3; anything else wraps around,
/// as tcnn does) to `level_count() * 2` features, level-major: features [2l, 2l+1] come from
/// level l. Parameters are not owned: every call takes a pointer to the grid's block of the
/// flat parameter vector, laid out entry-major (`(level.offset + index) * 2 + feature`).
#include <tdf/core/vec.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace tdf {

/// Encoding hyper-parameters; the defaults are the reference's (spec 4.1).
struct HashGridConfig {
    int levels = 16;               ///< number of resolution levels, 1..kMaxLevels
    int log2_table_size = 15;      ///< entries per hashed level = 2^log2_table_size, 4..24
    int base_resolution = 16;      ///< resolution parameter of level 0, >= 2
    float per_level_scale = 1.5f;  ///< growth of the scale from one level to the next, >= 1
};

/// One level of the grid.
struct HashGridLevel {
    float scale = 0;                 ///< pos = scale * x + 0.5 (tcnn `grid_scale`)
    std::uint32_t resolution = 0;    ///< ceil(scale) + 1 cells per axis (tcnn `grid_resolution`)
    std::uint32_t table_size = 0;    ///< entries of this level (multiple of 8)
    std::uint32_t offset = 0;        ///< first entry of this level in the grid
    bool hashed = false;             ///< true: CoherentPrime hash; false: dense stride indexing
    std::uint64_t modulo_magic = 0;  ///< Lemire fastmod constant for `% table_size`
};

/// Grid-space points as structure-of-arrays: coordinate d of point i is `coord[d][i]`, already
/// passed through HashGrid::sanitize_coordinate. The input of the block functions.
struct GridPointArrays {
    const float* coord[3];
};

/// The 8 trilinear corners of one level around one point.
struct GridCorners {
    std::uint32_t index[8];  ///< entry index inside the level, < table_size
    float weight[8];         ///< trilinear weights, sum 1; bit 0 of the corner = +x, bit 1 = +y, bit 2 = +z
};

class HashGrid {
public:
    static constexpr int kFeaturesPerLevel = 2;
    static constexpr int kMaxLevels = 32;

    /// Throws tdf::Error when a value is out of the documented range.
    explicit HashGrid(const HashGridConfig& config);

    const HashGridConfig& config() const { return m_config; }
    const std::vector<HashGridLevel>& levels() const { return m_levels; }
    int level_count() const { return int(m_levels.size()); }
    /// Length of the encoding: level_count() * 2 (32 for the defaults).
    int feature_count() const { return level_count() * kFeaturesPerLevel; }
    /// Table entries over all levels (476,672 for the defaults).
    std::size_t entry_count() const { return m_entry_count; }
    /// Floats of the grid's parameter block: entry_count() * 2 (953,344 for the defaults).
    std::size_t parameter_count() const { return m_entry_count * kFeaturesPerLevel; }

    /// Largest accepted |grid coordinate|; beyond it coordinates are clamped (the grid wraps
    /// long before, and the clamp keeps every level's cell index inside the int range).
    static constexpr float kMaxCoordinate = 1000.0f;
    /// Clamps a grid coordinate to [-kMaxCoordinate, kMaxCoordinate]; NaN becomes 0.
    static float sanitize_coordinate(float v) {
        return v >= -kMaxCoordinate ? (v <= kMaxCoordinate ? v : kMaxCoordinate)
                                    : (v < 0 ? -kMaxCoordinate : 0.0f);
    }

    /// The corners and weights of level `level` around grid-space point `x` (tcnn
    /// `pos_fract` + `grid_index`, wrapping uint32 arithmetic included).
    inline void corners(int level, Vec3f x, GridCorners& out) const;

    /// Points per call of the batched functions below.
    static constexpr std::size_t kBatch = 64;

    /// Writes the feature_count() features of grid-space point `x` to `features`.
    void encode(const float* grid_params, Vec3f x, float* features) const {
        encode_batch(grid_params, &x, 1, features, 1);
    }

    /// Encodes `count` <= kBatch grid-space points `x`, feature-major: feature k of point i goes
    /// to `features[k * stride + i]` (stride >= count), the layout the heads read 8 points per
    /// instruction. Same results as encode_levels().
    void encode_batch(const float* grid_params, const Vec3f* x, std::size_t count, float* features,
                      std::size_t stride) const;

    /// Encodes any number of points, feature-major like encode_batch(), level by level: all
    /// `count` points read level 0's table, then level 1's, and so on, so one level's table
    /// (<= 256 KiB for the defaults) is read by many points in a row. Corner indices are
    /// computed kBatch points at a time (vectorized) and prefetched before they are read.
    void encode_levels(const float* grid_params, const GridPointArrays& x, std::size_t count, float* features,
                       std::size_t stride) const;

    /// Adds d(features of `level`)/d(grid params)^T * d for `count` points: for point i,
    /// (d0[i], d1[i]) (dL/d features 2l, 2l+1) is spread over its 8 corners, in point order (so
    /// the sums are deterministic). Points with d = (0,0) are skipped.
    void accumulate_level_gradient(int level, const GridPointArrays& x, std::size_t count, const float* d0,
                                   const float* d1, float* grid_gradient) const;

private:
    HashGridConfig m_config;
    std::vector<HashGridLevel> m_levels;
    std::size_t m_entry_count = 0;
};

namespace detail {
__extension__ typedef unsigned __int128 HashGridU128;
/// a % d for 32-bit a via one 128-bit multiply (Lemire, Kaser, Kurz 2019); magic = 2^64/d + 1.
inline std::uint32_t fast_mod(std::uint32_t a, std::uint64_t magic, std::uint32_t d) {
    const std::uint64_t low = magic * a;
    return std::uint32_t((HashGridU128(low) * d) >> 64);
}
}  // namespace detail

inline void HashGrid::corners(int level, Vec3f x, GridCorners& out) const {
    const HashGridLevel& l = m_levels[std::size_t(level)];
    std::uint32_t g[3];
    float w1[3];
    for (int d = 0; d < 3; ++d) {
        // tcnn uses fmaf here; a plain multiply-add differs by at most one rounding, which only
        // matters for exact weight transfer (impossible anyway, spec 4.2).
        const float pos = l.scale * sanitize_coordinate(x[d]) + 0.5f;
        // floor via truncation (std::floor is a libm call without SSE4.1); sanitize_coordinate
        // keeps pos inside the int range.
        int cell = int(pos);
        cell -= int(pos < float(cell));
        g[d] = std::uint32_t(cell);
        w1[d] = pos - float(cell);
    }
    std::uint32_t ax[2], ay[2], az[2];
    if (l.hashed) {
        // CoherentPrime hash (tcnn `coherent_prime_hash`): x * 1 ^ y * 2654435761 ^ z * 805459861.
        ax[0] = g[0], ax[1] = g[0] + 1u;
        ay[0] = g[1] * 2654435761u, ay[1] = (g[1] + 1u) * 2654435761u;
        az[0] = g[2] * 805459861u, az[1] = (g[2] + 1u) * 805459861u;
        const std::uint32_t mask = l.table_size - 1u;  // hashed tables are powers of two
        for (int c = 0; c < 8; ++c) out.index[c] = (ax[c & 1] ^ ay[(c >> 1) & 1] ^ az[c >> 2]) & mask;
    } else {
        // Dense stride indexing in wrapping uint32 arithmetic, then modulo (tcnn `grid_index`):
        // the +0.5 offset and negative raw coordinates wrap around instead of failing.
        const std::uint32_t r = l.resolution, r2 = l.resolution * l.resolution;
        ax[0] = g[0], ax[1] = g[0] + 1u;
        ay[0] = g[1] * r, ay[1] = (g[1] + 1u) * r;
        az[0] = g[2] * r2, az[1] = (g[2] + 1u) * r2;
        for (int c = 0; c < 8; ++c)
            out.index[c] =
                detail::fast_mod(ax[c & 1] + ay[(c >> 1) & 1] + az[c >> 2], l.modulo_magic, l.table_size);
    }
    const float wx[2] = {1.0f - w1[0], w1[0]}, wy[2] = {1.0f - w1[1], w1[1]}, wz[2] = {1.0f - w1[2], w1[2]};
    for (int c = 0; c < 8; ++c) out.weight[c] = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
}

}  // namespace tdf
