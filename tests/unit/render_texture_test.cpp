#include <tdf/core/error.h>
#include <tdf/render/texture.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

using namespace tdf;

namespace {
// Points in the batched lookups' form (UvLanes: an array per component).
struct SoaPoints {
    std::vector<float> u, v, du_dx, dv_dx, du_dy, dv_dy;
    SoaPoints(const std::vector<Vec2f>& uv, const std::vector<Vec2f>& dx, const std::vector<Vec2f>& dy) {
        for (std::size_t i = 0; i < uv.size(); ++i) {
            u.push_back(uv[i].x), v.push_back(uv[i].y);
            du_dx.push_back(dx[i].x), dv_dx.push_back(dx[i].y), du_dy.push_back(dy[i].x),
                dv_dy.push_back(dy[i].y);
        }
    }
    UvLanes lanes() const {
        return {u.data(), v.data(), du_dx.data(), dv_dx.data(), du_dy.data(), dv_dy.data()};
    }
};

// 2x2 single-channel texture, rows top to bottom: [1 2; 3 4].
MipTexture two_by_two() {
    Image img(2, 2, 1);
    img.at(0, 0, 0) = 1;
    img.at(1, 0, 0) = 2;
    img.at(0, 1, 0) = 3;
    img.at(1, 1, 0) = 4;
    return MipTexture(img);
}
}  // namespace

TEST(MipTexture, BilinearUsesTexelCentresAndVUp) {
    const MipTexture tex = two_by_two();
    float out = 0;
    // Texel (0,0) (top-left) centre: u = 0.25, v' = 0.25 -> v = 0.75.
    tex.sample_bilinear({0.25f, 0.75f}, &out);
    EXPECT_FLOAT_EQ(out, 1.f);
    tex.sample_bilinear({0.75f, 0.25f}, &out);  // bottom-right texel
    EXPECT_FLOAT_EQ(out, 4.f);
    tex.sample_bilinear({0.5f, 0.5f}, &out);  // centre: average of all four
    EXPECT_FLOAT_EQ(out, 2.5f);
    // x = 0.6 * 2 - 0.5 = 0.7, y = (1 - 0.9) * 2 - 0.5 = -0.3 -> wraps to rows 1 (w .3) and 0 (w .7).
    tex.sample_bilinear({0.6f, 0.9f}, &out);
    const float top = 0.3f * 1 + 0.7f * 2, bottom = 0.3f * 3 + 0.7f * 4;
    EXPECT_NEAR(out, 0.3f * bottom + 0.7f * top, 1e-6f);
    // Wrap addressing: u = 0 blends the last and first columns equally.
    tex.sample_bilinear({0.f, 0.75f}, &out);
    EXPECT_FLOAT_EQ(out, 1.5f);
    tex.sample_bilinear({3.f, 0.75f}, &out);
    EXPECT_FLOAT_EQ(out, 1.5f);
}

TEST(MipTexture, PyramidIsABoxFilterDownToOneTexel) {
    Image img(4, 2, 2);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            img.at(x, y, 0) = float(x + 4 * y);
            img.at(x, y, 1) = 1.f;
        }
    const MipTexture tex(img);
    ASSERT_EQ(tex.level_count(), 3);  // 4x2, 2x1, 1x1
    EXPECT_FLOAT_EQ(tex.level(1).at(0, 0, 0), (0 + 1 + 4 + 5) / 4.f);
    EXPECT_FLOAT_EQ(tex.level(1).at(1, 0, 0), (2 + 3 + 6 + 7) / 4.f);
    EXPECT_FLOAT_EQ(tex.level(2).at(0, 0, 0), 3.5f);
    EXPECT_FLOAT_EQ(tex.level(2).at(0, 0, 1), 1.f);
}

TEST(MipTexture, DroppedLevelsComeBackBitForBit) {
    Image img(37, 20, 3);
    for (std::size_t k = 0; k < img.values().size(); ++k) img.values()[k] = std::sin(0.37f * float(k)) + 0.1f;
    const MipTexture reference(img);
    MipTexture tex(img);
    tex.drop_levels();
    ASSERT_EQ(tex.level_count(), 1);
    EXPECT_EQ(tex.level(0).values(), img.values());
    tex.restore_levels();
    ASSERT_EQ(tex.level_count(), reference.level_count());
    for (int k = 0; k < tex.level_count(); ++k) {
        SCOPED_TRACE(k);
        EXPECT_EQ(tex.level(k).width(), reference.level(k).width());
        EXPECT_EQ(tex.level(k).values(), reference.level(k).values());  // vectors of float: exact
    }
}

TEST(MipTexture, OddSizesKeepTheMean) {
    Image img(5, 3, 1);
    double sum = 0;
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) sum += img.at(x, y, 0) = float((x * 7 + y * 3) % 5);
    const MipTexture tex(img);
    ASSERT_EQ(tex.level(1).width(), 2);
    ASSERT_EQ(tex.level(1).height(), 1);
    EXPECT_NEAR(tex.level(tex.level_count() - 1).at(0, 0, 0), sum / 15, 1e-5);
    // Level 1 texel 0 averages columns [0, 2.5) of all rows.
    double expect = 0;
    for (int y = 0; y < 3; ++y) expect += img.at(0, y, 0) + img.at(1, y, 0) + 0.5 * img.at(2, y, 0);
    EXPECT_NEAR(tex.level(1).at(0, 0, 0), expect / 7.5, 1e-5);
}

TEST(MipTexture, TrilinearLodFromJacobian) {
    Image img(8, 8, 1);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) img.at(x, y, 0) = float((x + y) % 2);  // checker: mean 0.5
    const MipTexture tex(img);
    // One texel per pixel -> LOD 0; 2 texels per pixel along x -> LOD 1; anisotropic: major axis.
    EXPECT_NEAR(tex.level_of_detail({1.f / 8, 0}, {0, 1.f / 8}), 0.f, 1e-6f);
    EXPECT_NEAR(tex.level_of_detail({2.f / 8, 0}, {0, 1.f / 8}), 1.f, 1e-6f);
    EXPECT_NEAR(tex.level_of_detail({0, 0}, {0, -4.f / 8}), 2.f, 1e-6f);
    float out = 0, l0 = 0, l1 = 0;
    const Vec2f uv{0.3f, 0.6f};
    tex.sample_level(0, uv, &l0);
    tex.sample_level(1, uv, &l1);
    // LOD 0.5: halfway between levels 0 and 1.
    const float d = std::sqrt(2.f) / 8;
    tex.sample_trilinear(uv, {d, 0}, {0, d}, &out);
    EXPECT_NEAR(out, 0.5f * (l0 + l1), 1e-6f);
    // Level 1 of a 1-texel checker is uniform 0.5; a huge footprint reaches the 1x1 level.
    tex.sample_trilinear(uv, {100, 0}, {0, 100}, &out);
    EXPECT_NEAR(out, 0.5f, 1e-6f);
    // Magnification clamps to level 0; max_level caps the LOD.
    tex.sample_trilinear(uv, {1e-4f, 0}, {0, 1e-4f}, &out);
    EXPECT_FLOAT_EQ(out, l0);
    tex.sample_trilinear(uv, {100, 0}, {0, 100}, &out, 1);
    EXPECT_FLOAT_EQ(out, l1);
}

TEST(MipTexture, EmptyImageIsAnError) {
    const Image empty;
    EXPECT_THROW(MipTexture{empty}, Error);
}

// The renderer's batched lookups (one tile at a time, compiled for AVX-512, AVX2 and the baseline
// and picked at load time) give the single lookups' bits: LOD included, for RGB pairs and for
// other channel counts, with points skipped where nothing was hit.
TEST(MipTexture, BatchedPairLookupsEqualTheSingleOnesBitForBit) {
    for (const int channels : {3, 4}) {
        Image a(64, 48, channels), b(64, 48, 3);
        for (int y = 0; y < 48; ++y)
            for (int x = 0; x < 64; ++x) {
                for (int k = 0; k < channels; ++k) a.at(x, y, k) = std::sin(0.37f * float(x * (k + 1)) + 0.11f * float(y));
                for (int k = 0; k < 3; ++k) b.at(x, y, k) = std::cos(0.23f * float(x) - 0.41f * float(y * (k + 2)));
            }
        const MipTexture ta(a), tb(b);
        constexpr std::size_t n = 300;
        std::vector<float> covered(n), lod(n);
        std::vector<Vec2f> uv(n), dx(n), dy(n);
        for (std::size_t i = 0; i < n; ++i) {
            const float s = float(i);
            covered[i] = i % 7 == 3 ? 0.f : 1.f;
            // UVs outside [0, 1) wrap; footprints from magnified (LOD < 0) to beyond the top level.
            uv[i] = {std::fmod(s * 0.173f, 3.f) - 1.f, std::fmod(s * 0.291f, 2.5f) - 0.7f};
            const float scale = std::exp2(float(int(i % 19)) - 9.f) * (1.f + 0.01f * s);
            dx[i] = {scale * std::cos(s), scale * 0.3f * std::sin(s)};
            dy[i] = {-scale * 0.5f * std::sin(2.f * s), scale * std::cos(3.f * s)};
        }
        dx[5] = dy[5] = {};  // a zero footprint
        std::vector<float> out_a(n * std::size_t(channels), -7.f), out_b(n * 3, -7.f);
        for (const int max_level : {-1, 2}) {
            const SoaPoints points(uv, dx, dy);
            ta.sample_trilinear_pairs(
                tb, n, covered.data(), points.lanes(), lod.data(), out_a.data(), out_b.data(), n, max_level);
            std::size_t compared = 0;
            for (std::size_t i = 0; i < n; ++i) {
                if (!(covered[i] > 0.f)) continue;
                float want_a[kMaxTextureChannels], want_b[kMaxTextureChannels];
                ta.sample_trilinear_pair_at(tb, uv[i], ta.level_of_detail(dx[i], dy[i]), want_a, want_b, max_level);
                for (int k = 0; k < channels; ++k)
                    ASSERT_EQ(std::memcmp(&want_a[k], &out_a[std::size_t(k) * n + i], 4), 0)
                        << "channels " << channels << " point " << i << " channel " << k;
                for (int k = 0; k < 3; ++k)
                    ASSERT_EQ(std::memcmp(&want_b[k], &out_b[std::size_t(k) * n + i], 4), 0) << "point " << i;
                ++compared;
            }
            EXPECT_EQ(compared, n - n / 7 - (n % 7 > 3 ? 1 : 0));
        }
    }
}

// The same for the points the gather kernels take (AVX-512 or AVX2, where the CPU and the build's
// SIMD list have them; texture_lanes.h): UVs inside [0, 1] on power-of-two and other sizes,
// LODs that cross levels within a group of lanes, magnification, max_level caps, groups cut short
// at the end and by uncovered points, and the points the kernels leave to the scalar code (UVs
// that wrap, NaN) mixed in.
TEST(MipTexture, GatheredPairLookupsEqualTheSingleOnesBitForBit) {
    for (const int size : {256, 100}) {
        Image a(size, size, 3), b(size, size, 3);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                for (int k = 0; k < 3; ++k) {
                    a.at(x, y, k) = std::sin(0.31f * float(x * (k + 1)) + 0.13f * float(y));
                    b.at(x, y, k) = std::cos(0.19f * float(x) - 0.37f * float(y * (k + 2)));
                }
        const MipTexture ta(a), tb(b);
        constexpr std::size_t n = 1000;
        std::vector<float> covered(n), lod(n);
        std::vector<Vec2f> uv(n), dx(n), dy(n);
        for (std::size_t i = 0; i < n; ++i) {
            const float s = float(i);
            covered[i] = i % 23 == 5 || (i >= 300 && i < 340) ? 0.f : 1.f;
            uv[i] = {std::fmod(s * 0.0137f, 1.f), 1.f - std::fmod(s * 0.0071f, 1.f)};
            // LODs from -2 to about 9 that change every few points.
            const float scale = std::exp2(s * 0.011f - 2.f + 0.5f * std::sin(s)) / float(size);
            dx[i] = {scale, 0.2f * scale * std::sin(s)};
            dy[i] = {0.1f * scale * std::cos(s), scale};
        }
        uv[17] = {1.f, 0.f}, uv[18] = {0.f, 1.f}, uv[19] = {0.9999999f, 1e-7f};  // the edges
        uv[40] = {1.25f, 0.5f}, uv[41] = {0.5f, -0.5f};  // wrap: left to the scalar code
        uv[42] = {std::nanf(""), 0.5f};
        constexpr std::size_t plane = n + 3;  // planes further apart than n
        std::vector<float> out_a(plane * 3, -7.f), out_b(plane * 3, -7.f);
        for (const int max_level : {-1, 3, 0}) {
            const SoaPoints points(uv, dx, dy);
            ta.sample_trilinear_pairs(tb,
                                      n,
                                      covered.data(),
                                      points.lanes(),
                                      lod.data(),
                                      out_a.data(),
                                      out_b.data(),
                                      plane,
                                      max_level);
            for (std::size_t i = 0; i < n; ++i) {
                if (!(covered[i] > 0.f)) {
                    for (std::size_t k = 0; k < 3; ++k)
                        ASSERT_TRUE(out_a[k * plane + i] == -7.f && out_b[k * plane + i] == -7.f)
                            << "uncovered point " << i << " was written";
                    continue;
                }
                float want_a[3], want_b[3];
                ta.sample_trilinear_pair_at(
                    tb, uv[i], ta.level_of_detail(dx[i], dy[i]), want_a, want_b, max_level);
                const float got_a[3] = {out_a[i], out_a[plane + i], out_a[2 * plane + i]};
                const float got_b[3] = {out_b[i], out_b[plane + i], out_b[2 * plane + i]};
                ASSERT_EQ(std::memcmp(want_a, got_a, sizeof want_a), 0)
                    << "size " << size << " max_level " << max_level << " point " << i;
                ASSERT_EQ(std::memcmp(want_b, got_b, sizeof want_b), 0)
                    << "size " << size << " max_level " << max_level << " point " << i;
            }
        }
    }
}

// The batched single-map lookups (the visualizer's tactile map, a map laid at a UV scale) give
// sample_trilinear_at's bits at level_of_detail + the scale's LOD offset.
TEST(MipTexture, BatchedLookupsEqualTheSingleOnesBitForBit) {
    for (const int channels : {3, 1}) {
        Image img(40, 24, channels);
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 40; ++x)
                for (int k = 0; k < channels; ++k) img.at(x, y, k) = std::sin(0.29f * float(x * (k + 1)) - 0.17f * float(y));
        const MipTexture tex(img);
        constexpr std::size_t n = 257;
        std::vector<float> covered(n), lod(n), out(n * std::size_t(channels), -7.f);
        std::vector<Vec2f> uv(n), dx(n), dy(n);
        for (std::size_t i = 0; i < n; ++i) {
            const float s = float(i);
            covered[i] = i % 5 == 1 ? 0.f : 1.f;
            uv[i] = {std::fmod(s * 0.137f, 2.f) - 0.5f, std::fmod(s * 0.311f, 3.f) - 1.2f};
            const float scale = std::exp2(float(int(i % 17)) - 8.f);
            dx[i] = {scale * std::cos(2.f * s), scale * std::sin(s)};
            dy[i] = {scale * 0.4f * std::sin(3.f * s), scale * std::cos(s)};
        }
        for (const float uv_scale : {1.f, 11.9f})
            for (const int max_level : {-1, 5, 1}) {
                const float offset = std::log2(uv_scale);
                const SoaPoints points(uv, dx, dy);
                tex.sample_trilinear_many(n,
                                          covered.data(),
                                          points.lanes(),
                                          uv_scale,
                                          offset,
                                          lod.data(),
                                          out.data(),
                                          n,
                                          max_level);
                for (std::size_t i = 0; i < n; ++i) {
                    if (!(covered[i] > 0.f)) continue;
                    float want[kMaxTextureChannels];
                    tex.sample_trilinear_at(uv[i] * uv_scale, tex.level_of_detail(dx[i], dy[i]) + offset, want, max_level);
                    for (int k = 0; k < channels; ++k)
                        ASSERT_EQ(std::memcmp(&want[k], &out[std::size_t(k) * n + i], 4), 0)
                            << "channels " << channels << " scale " << uv_scale << " max_level " << max_level
                            << " point " << i;
                }
            }
    }
}

TEST(MipTextureDeathTest, BatchedPairLookupsNeedMapsOfOneSize) {
    const MipTexture a(Image(8, 8, 3)), b(Image(8, 4, 3));
    float covered = 1.f, lod = 0.f, out_a[3], out_b[3];
    const Vec2f uv{0.5f, 0.5f}, d{0.1f, 0.f};
    const SoaPoints points({uv}, {d}, {d});
    EXPECT_DEATH(a.sample_trilinear_pairs(b, 1, &covered, points.lanes(), &lod, out_a, out_b, 1),
                 "internal check failed");
}
