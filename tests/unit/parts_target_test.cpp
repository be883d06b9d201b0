// The composed multi-part tactile target: bleeding and seams at part boundaries (measured),
// mip levels that do not mix parts, and the label map / mask exports.
#include <tdf/core/error.h>
#include <tdf/core/rng.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/part_target.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace tdf;

namespace {

// A smooth random tileable normal map (slopes from a few random sinusoids).
Image random_normals(std::uint64_t seed, int size, float amplitude) {
    Rng rng(seed);
    struct Wave {
        int fx, fy;
        float phase, a;
    };
    std::vector<Wave> waves;
    for (int k = 0; k < 12; ++k)
        waves.push_back(
            {rng.uniform_int(1, 9), rng.uniform_int(1, 9), rng.uniform(0.f, 6.28f), rng.uniform(0.5f, 1.f)});
    Image img(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            float sx = 0, sy = 0;
            for (const Wave& w : waves) {
                const float arg = 6.2831853f * (float(w.fx * x) + float(w.fy * y)) / float(size) + w.phase;
                sx += w.a * float(w.fx) * std::cos(arg);
                sy += w.a * float(w.fy) * std::cos(arg);
            }
            const Vec3f n = safe_normalize({-amplitude * sx, -amplitude * sy, 1.f});
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = n[c];
        }
    return img;
}

// Labels: part 0 inside a disc, part 1 outside it, background in the corners' last rows.
std::vector<int> disc_labels(int size) {
    std::vector<int> l(std::size_t(size) * std::size_t(size));
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float dx = float(x) + 0.5f - float(size) / 2, dy = float(y) + 0.5f - float(size) / 2;
            l[std::size_t(y) * std::size_t(size) + std::size_t(x)] =
                y >= size - 4                                    ? -1
                : dx * dx + dy * dy < float(size * size) * 0.09f ? 0
                                                                 : 1;
        }
    return l;
}

}  // namespace

TEST(PartTarget, LaysEachMapWithItsLayout) {
    const MipTexture a(random_normals(1, 64, 0.02f));
    const std::vector<Image> layers = lay_part_maps({{&a, 1.f}, {&a, 2.f}}, 128);
    ASSERT_EQ(layers.size(), 2u);
    // uv_scale 1 on a 2x larger atlas: texel (2x, 2y) interpolates between source texels; uv_scale 2
    // repeats the map twice, so its texel (x, y) and (x + 64, y) agree.
    for (int y = 0; y < 128; y += 7)
        for (int x = 0; x < 64; x += 5)
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(layers[1].at(x, y, c), layers[1].at(x + 64, y, c), 1e-5f);
    EXPECT_THROW(lay_part_maps({{nullptr, 1.f}}, 16), Error);
}

TEST(PartTarget, BoundaryBleedsAtMostTwoTexelsWithoutAVisibleSeam) {
    const int size = 256;
    const MipTexture a(random_normals(11, size, 0.004f)), b(random_normals(12, size, 0.004f));
    const std::vector<Image> layers = lay_part_maps({{&a, 1.f}, {&b, 1.f}}, size);
    const std::vector<int> labels = disc_labels(size);
    const Image hard = compose_part_target(labels, size, layers, 0.f);
    const Image soft = compose_part_target(labels, size, layers);
    const PartBoundaryMeasure h = measure_part_boundary(hard, labels, size, layers);
    const PartBoundaryMeasure s = measure_part_boundary(soft, labels, size, layers);
    for (const auto& [what, r] :
         {std::pair<const char*, PartBoundaryMeasure>{"hard cut", h}, {"band 1.5", s}})
        std::printf(
            "%-8s bleed %.2f texels, boundary step %.3f deg (hard cut %.3f, ratio %.2f), band detail %.3f, "
            "interior step %.3f deg\n",
            what,
            r.bleed_texels,
            r.boundary_step_degrees,
            r.hard_step_degrees,
            r.step_ratio,
            r.band_detail_ratio,
            r.interior_step_degrees);
    EXPECT_EQ(h.bleed_texels, 0.0);
    EXPECT_NEAR(h.step_ratio, 1.0, 1e-9);
    EXPECT_LE(s.bleed_texels, 2.0);
    EXPECT_GT(s.boundary_pairs, 100u);
    // The cross-fade spreads the jump between the two textures over the band (no line where
    // they meet) and keeps the relief's strength in it (no flattened line either).
    EXPECT_LT(s.step_ratio, 0.7);
    EXPECT_NEAR(s.band_detail_ratio, 1.0, 0.1);
    // A plain average of the normals would flatten the band: the slope blend is what avoids it.
    const Vec3f a3{0.3f, 0.f, 1.f}, b3{-0.3f, 0.f, 1.f};
    EXPECT_NEAR(blend_normals(a3, b3, 1.f).x, safe_normalize(a3).x, 1e-6f);
    EXPECT_NEAR(blend_normals(a3, b3, 0.75f).x / blend_normals(a3, b3, 0.75f).z,
                0.3f * 0.5f / std::sqrt(0.625f),
                1e-5f);
    // Unit normals everywhere, flat on the background.
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const float* p = soft.data() + i * 3;
        EXPECT_NEAR(p[0] * p[0] + p[1] * p[1] + p[2] * p[2], 1.f, 1e-4f);
        if (labels[i] < 0) {
            EXPECT_EQ(p[2], 1.f);
        }
    }
}

TEST(PartTarget, BoxPyramidMixesPartsOnlyWhereTheFootprintHoldsBoth) {
    const int size = 128;
    const MipTexture a(random_normals(21, size, 0.01f)), b(random_normals(22, size, 0.01f));
    const std::vector<Image> layers = lay_part_maps({{&a, 1.f}, {&b, 1.f}}, size);
    const std::vector<int> labels = disc_labels(size);
    const Image level0 = compose_part_target(labels, size, layers);
    const MipTexture box(level0);
    std::vector<MipTexture> mips;
    for (const Image& l : layers) mips.emplace_back(l);
    // Level-0 texels that are not purely their own part's map: the band, and the other part.
    std::vector<int> pure(labels.size(), 0);
    for (std::size_t i = 0; i < labels.size(); ++i)
        if (labels[i] >= 0) {
            const float* c = level0.data() + i * 3;
            const float* o = layers[std::size_t(labels[i])].data() + i * 3;
            pure[i] = c[0] == o[0] && c[1] == o[1] && c[2] == o[2];
        }
    for (int k = 1; k <= 4; ++k) {
        const int sk = size >> k, f = 1 << k;
        std::size_t mixed = 0, total = 0, unexplained = 0;
        for (int y = 0; y < sk; ++y)
            for (int x = 0; x < sk; ++x) {
                // The footprint's parts; the texel's own part is the one every footprint texel has.
                int own = -2;
                bool one_part_pure = true;
                for (int dy = 0; dy < f; ++dy)
                    for (int dx = 0; dx < f; ++dx) {
                        const std::size_t i = std::size_t(y * f + dy) * std::size_t(size) + std::size_t(x * f + dx);
                        if (labels[i] < 0) {  // the flat background is averaged in too
                            one_part_pure = false;
                            continue;
                        }
                        if (own == -2) own = labels[i];
                        if (labels[i] != own || !pure[i]) one_part_pure = false;
                    }
                if (own < 0) continue;
                ++total;
                const Image& o = mips[std::size_t(own)].level(k);
                const Vec3f n = safe_normalize({o.at(x, y, 0), o.at(x, y, 1), o.at(x, y, 2)});
                const Image& img = box.level(k);
                const Vec3f p = safe_normalize({img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)});
                const bool off = std::acos(std::min(1.f, dot(p, n))) * 57.29578f > 1.f;
                mixed += off;
                // A texel whose whole footprint is pure single-part texels must not be mixed.
                unexplained += off && one_part_pure;
            }
        std::printf("level %d (%dx%d): %.1f %% of texels mix parts (all where the footprint holds both, the band or background)\n", k,
                    sk, sk, 100.0 * double(mixed) / double(total));
        EXPECT_EQ(unexplained, 0u) << "level " << k;
    }
}

TEST(PartTarget, LabelHelpers) {
    // 2x2 majority with ties to the lowest label; all-empty stays empty.
    const std::vector<int> l = {0, 1, 2, 2, 1, 0, 2, -1, -1, -1, 3, 3, -1, -1, 3, 1};
    EXPECT_EQ(downsample_labels(l, 4), (std::vector<int>{0, 2, -1, 3}));
    // Dilation fills the gutter from the neighbouring part only `texels` rings deep.
    std::vector<int> d(25, -1);
    d[0] = 1;
    const std::vector<int> grown = dilate_labels(d, 5, 2);
    EXPECT_EQ(grown[12], 1);   // (2, 2)
    EXPECT_EQ(grown[18], -1);  // (3, 3)
    EXPECT_EQ(part_mask(grown, 5, 1).at(1, 1, 0), 1.f);
}

TEST(PartTarget, WritesLabelMapLegendAndMasks) {
    const int size = 32;
    std::vector<int> labels = disc_labels(size);
    const std::string base = test::scratch_dir() + "/parts_export/cactus";
    const Json legend = write_part_maps(base, labels, size, {"cap", "base"}, 2);
    const Image map = read_image(base + "_label_map.png");
    ASSERT_EQ(map.width(), size);
    EXPECT_EQ(map.at(16, 16, 0), 1.f);  // part 0 red (spec 7.4: R = part A)
    EXPECT_EQ(map.at(16, 16, 1), 0.f);
    EXPECT_EQ(map.at(1, 1, 1), 1.f);         // part 1 green
    EXPECT_EQ(map.at(1, size - 3, 1), 1.f);  // background row inside the 2-texel gutter: dilated
    EXPECT_EQ(map.at(1, size - 1, 1), 0.f);  // beyond it: black
    const Image cap = read_image(base + "_mask_cap.png");
    EXPECT_EQ(cap.at(16, 16, 0), 1.f);
    EXPECT_EQ(cap.at(1, 1, 0), 0.f);
    const Json written = load_json_file(base + "_label_legend.json");
    EXPECT_EQ(written["parts"][1]["name"], "base");
    EXPECT_EQ(written["parts"][0]["colour"], Json::array({255, 0, 0}));
    EXPECT_NEAR(legend[0]["fraction"].get<double>() + legend[1]["fraction"].get<double>(), 1.0, 1e-9);
    EXPECT_EQ(part_colour(7).x, part_colour(7).x);
    EXPECT_NE(part_colour(6).x + part_colour(6).y + part_colour(6).z, 0.f);
}
