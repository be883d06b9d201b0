#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/field/hash_grid.h>

#include <cmath>
#include <vector>

using namespace tdf;

TEST(HashGrid, LevelResolutionsMatchReference) {
    const HashGrid grid(HashGridConfig{});
    // Spec 4.2: res_l = ceil(scale_l) + 1 with float32 scale_l = 2^(l log2 1.5) * 16 - 1.
    const std::uint32_t expected[16] = {
        16, 24, 36, 54, 81, 122, 183, 274, 411, 616, 923, 1384, 2076, 3114, 4671, 7007};
    ASSERT_EQ(grid.level_count(), 16);
    for (int l = 0; l < 16; ++l)
        EXPECT_EQ(grid.levels()[std::size_t(l)].resolution, expected[l]) << "level " << l;
    EXPECT_EQ(grid.levels()[0].table_size, 4096u);
    EXPECT_EQ(grid.levels()[1].table_size, 13824u);
    EXPECT_FALSE(grid.levels()[0].hashed);
    EXPECT_FALSE(grid.levels()[1].hashed);
    for (int l = 2; l < 16; ++l) {
        EXPECT_EQ(grid.levels()[std::size_t(l)].table_size, 32768u);
        EXPECT_TRUE(grid.levels()[std::size_t(l)].hashed);
    }
    EXPECT_EQ(grid.entry_count(), 476672u);
    EXPECT_EQ(grid.parameter_count(), 953344u);
    EXPECT_EQ(grid.feature_count(), 32);
}

TEST(HashGrid, CornerIndicesFollowTcnnRules) {
    const HashGrid grid(HashGridConfig{});
    GridCorners c;
    // Dense level 0: scale 15, res 16; x = 0.3 -> pos 5.0 -> cell 5, weight 0 on the + side.
    grid.corners(0, {0.3f, 0.5f, 0.9f}, c);
    // pos = 15 x + 0.5 = (5.0, 8.0, 14.0); index = gx + 16 gy + 256 gz.
    EXPECT_EQ(c.index[0], 5u + 16u * 8u + 256u * 14u);
    EXPECT_EQ(c.index[7], (6u + 16u * 9u + 256u * 15u) % 4096u);
    // Negative raw coordinates wrap in uint32 before the modulo (tcnn behaviour).
    grid.corners(1, {-0.5f, 0.0f, 0.0f}, c);  // scale 23: pos -11.0 -> cell -11
    EXPECT_EQ(c.index[0], (std::uint32_t(-11) + 24u * 0u + 576u * 0u) % 13824u);
    // Hashed level 5: CoherentPrime hash masked to 2^15.
    const HashGridLevel& l5 = grid.levels()[5];
    const Vec3f x(0.31f, 0.77f, 0.12f);
    grid.corners(5, x, c);
    std::uint32_t g[3];
    for (int d = 0; d < 3; ++d) g[d] = std::uint32_t(int(std::floor(l5.scale * x[d] + 0.5f)));
    EXPECT_EQ(c.index[6], ((g[0]) ^ ((g[1] + 1) * 2654435761u) ^ ((g[2] + 1) * 805459861u)) & 32767u);
    float sum = 0;
    for (const float w : c.weight) sum += w;
    EXPECT_NEAR(sum, 1.0f, 1e-6f);
}

TEST(HashGrid, BatchEncodingEqualsPointByPointTrilinearInterpolation) {
    const HashGrid grid(HashGridConfig{});
    Rng rng(5);
    std::vector<float> params(grid.parameter_count());
    for (float& p : params) p = rng.uniform(-1, 1);
    std::vector<Vec3f> x(HashGrid::kBatch);
    for (Vec3f& p : x) p = {rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f), rng.uniform(-1.5f, 1.5f)};
    std::vector<float> batch(x.size() * 32);
    grid.encode_batch(params.data(), x.data(), x.size(), batch.data(), x.size());  // feature-major
    for (std::size_t i = 0; i < x.size(); ++i)
        for (int level = 0; level < 16; ++level) {
            GridCorners c;
            grid.corners(level, x[i], c);
            float f[2] = {0, 0};
            for (int k = 0; k < 8; ++k)
                for (int j = 0; j < 2; ++j)
                    f[j] +=
                        c.weight[k] *
                        params[(grid.levels()[std::size_t(level)].offset + c.index[k]) * 2 + std::size_t(j)];
            // Same operations in the same order: bit-identical.
            ASSERT_EQ(batch[std::size_t(2 * level) * x.size() + i], f[0])
                << "point " << i << " level " << level;
            ASSERT_EQ(batch[std::size_t(2 * level + 1) * x.size() + i], f[1])
                << "point " << i << " level " << level;
        }
}

TEST(HashGrid, FastModuloMatchesModulo) {
    Rng rng(6);
    for (const std::uint32_t d : {13824u, 4096u, 7u, 1u, 32768u, 4294967291u}) {
        const std::uint64_t magic = ~std::uint64_t(0) / d + 1;
        for (int i = 0; i < 10000; ++i) {
            const std::uint32_t a = rng.next_u32();
            ASSERT_EQ(detail::fast_mod(a, magic, d), a % d) << a << " % " << d;
        }
        EXPECT_EQ(detail::fast_mod(0xffffffffu, magic, d), 0xffffffffu % d);
    }
}

TEST(HashGrid, InvalidConfigIsRejected) {
    HashGridConfig c;
    c.levels = 0;
    EXPECT_THROW(HashGrid{c}, Error);
    c = {};
    c.per_level_scale = 0.5f;
    EXPECT_THROW(HashGrid{c}, Error);
    c = {};
    c.levels = 32;
    c.per_level_scale = 2.0f;  // level 31 would need scale 3.4e10
    EXPECT_THROW(HashGrid{c}, Error);
    // Non-finite and huge coordinates stay defined (clamped, NaN -> 0).
    EXPECT_EQ(HashGrid::sanitize_coordinate(std::nanf("")), 0.0f);
    EXPECT_EQ(HashGrid::sanitize_coordinate(1e30f), HashGrid::kMaxCoordinate);
    EXPECT_EQ(HashGrid::sanitize_coordinate(-INFINITY), -HashGrid::kMaxCoordinate);
}

TEST(HashGrid, LevelGradientEqualsPointByPointScatter) {
    // Coherent points (runs of points in one cell, as a render gives) and random ones; the tiny
    // table makes corners of one cell collide on the hashed levels.
    for (const int log2_table_size : {15, 4}) {
        HashGridConfig config;
        config.log2_table_size = log2_table_size;
        const HashGrid grid(config);
        Rng rng(7);
        const std::size_t n = 3000;
        std::vector<float> coord[3];
        std::vector<float> d0(n), d1(n);
        for (std::size_t i = 0; i < n; ++i) {
            const bool coherent = i < 2000;
            const float t = float(i) * 1e-4f;
            const Vec3f x = coherent ? Vec3f(0.3f + t, 0.6f - 0.5f * t, 0.45f)
                                     : Vec3f(rng.uniform(-0.2f, 1.2f), rng.uniform(0, 1), rng.uniform(0, 1));
            for (int d = 0; d < 3; ++d) coord[d].push_back(HashGrid::sanitize_coordinate(x[d]));
            d0[i] = i % 11 == 0 ? 0.0f : rng.uniform(-1, 1);  // some points carry no gradient
            d1[i] = i % 11 == 0 ? 0.0f : rng.uniform(-1, 1);
        }
        const GridPointArrays x{{coord[0].data(), coord[1].data(), coord[2].data()}};
        std::vector<float> fast(grid.parameter_count(), 0.5f), slow(grid.parameter_count(), 0.5f);
        for (int level = 0; level < grid.level_count(); ++level) {
            grid.accumulate_level_gradient(level, x, n, d0.data(), d1.data(), fast.data());
            const std::size_t offset = grid.levels()[std::size_t(level)].offset;
            for (std::size_t i = 0; i < n; ++i) {
                if (d0[i] == 0.0f && d1[i] == 0.0f) continue;
                GridCorners c;
                grid.corners(level, {coord[0][i], coord[1][i], coord[2][i]}, c);
                for (int k = 0; k < 8; ++k) {
                    slow[(offset + c.index[k]) * 2] += c.weight[k] * d0[i];
                    slow[(offset + c.index[k]) * 2 + 1] += c.weight[k] * d1[i];
                }
            }
        }
        // Same additions in the same order: bit-identical.
        for (std::size_t j = 0; j < fast.size(); ++j)
            ASSERT_EQ(fast[j], slow[j]) << "table 2^" << log2_table_size << " parameter " << j;
    }
}
