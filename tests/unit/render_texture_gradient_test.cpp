// The adjoint of trilinear sampling: recorded taps reproduce the lookup, and scattering a
// gradient through them then down the pyramid is the exact transpose of "build pyramid, sample"
// (dot-product test), checked against finite differences on level-0 texels too.
#include "common/test_images.h"
#include <tdf/core/rng.h>
#include <tdf/render/texture.h>
#include <tdf/render/texture_gradient.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

using namespace tdf;

namespace {
using test::inner_product;
using test::random_image;

struct Lookup {
    Vec2f uv;
    float lod;
};

std::vector<Lookup> random_lookups(std::size_t n, std::uint64_t seed) {
    Rng rng(seed);
    std::vector<Lookup> out(n);
    for (Lookup& l : out) l = {{rng.uniform() * 3.f - 1.f, rng.uniform() * 3.f - 1.f}, rng.uniform() * 7.f - 1.f};
    return out;
}

// L = sum_k <g_k, sample(lookup_k)>: linear in the base image, so its gradient is exact.
double loss(const MipTexture& tex, const std::vector<Lookup>& lookups, const std::vector<float>& g) {
    const int c = tex.channels();
    double sum = 0;
    std::vector<float> out(static_cast<std::size_t>(c));
    for (std::size_t k = 0; k < lookups.size(); ++k) {
        tex.sample_trilinear_at(lookups[k].uv, lookups[k].lod, out.data());
        for (int i = 0; i < c; ++i) sum += double(g[k * std::size_t(c) + std::size_t(i)]) * out[std::size_t(i)];
    }
    return sum;
}

}  // namespace

TEST(TextureGradient, TapsReproduceTrilinearLookups) {
    for (int size : {16, 13}) {  // power of two, and odd sizes (uneven box taps)
        const MipTexture tex(random_image(size, size + 3, 3, 7, 0.0f, 1.0f));
        float max_error = 0;
        for (const Lookup& l : random_lookups(2000, 11)) {
            for (int max_level : {-1, 2}) {
                float direct[3], from_taps[3];
                tex.sample_trilinear_at(l.uv, l.lod, direct, max_level);
                TrilinearTaps taps;
                tex.taps(l.uv, l.lod, max_level, taps);
                tex.gather(taps, from_taps);
                float weights = 0;
                for (int t = 0; t < taps.count; ++t) weights += taps.weight[t];
                EXPECT_NEAR(weights, 1.0f, 1e-6f);
                for (int c = 0; c < 3; ++c) max_error = std::max(max_error, std::fabs(direct[c] - from_taps[c]));
            }
        }
        EXPECT_LT(max_error, 2e-6f) << "size " << size;
    }
}

TEST(TextureGradient, ScatterAndCollapseAreTheTransposeOfSampling) {
    for (int size : {32, 21}) {
        const Image base = random_image(size, size, 2, 3, 0.0f, 1.0f);
        const MipTexture tex(base);
        const std::vector<Lookup> lookups = random_lookups(500, 5);
        std::vector<float> g(lookups.size() * 2);
        Rng rng(9);
        for (float& v : g) v = rng.uniform() * 2.f - 1.f;

        MipGradient grad;
        grad.reset(tex);
        for (std::size_t k = 0; k < lookups.size(); ++k) {
            TrilinearTaps taps;
            tex.taps(lookups[k].uv, lookups[k].lod, -1, taps);
            grad.add(taps, &g[2 * k]);
        }
        const Image& d_base = grad.collapse();
        // Dot-product test: L(base) = <d_base, base> because L is linear in base.
        double dot = 0;
        for (std::size_t i = 0; i < base.values().size(); ++i) dot += double(d_base.values()[i]) * base.values()[i];
        const double l = loss(tex, lookups, g);
        EXPECT_NEAR(dot, l, 1e-4 * std::max(1.0, std::fabs(l))) << "size " << size;

        // Finite differences on a few level-0 texels (central, h = 1e-2; exact up to rounding).
        double worst = 0;
        for (std::size_t i = 0; i < base.values().size(); i += 37) {
            Image plus = base, minus = base;
            plus.values()[i] += 1e-2f;
            minus.values()[i] -= 1e-2f;
            const double fd = (loss(MipTexture(plus), lookups, g) - loss(MipTexture(minus), lookups, g)) / 2e-2;
            worst = std::max(worst, std::fabs(fd - d_base.values()[i]));
        }
        EXPECT_LT(worst, 2e-3) << "size " << size;
    }
}

TEST(TextureGradient, AssignRebuildsThePyramidInPlace) {
    const Image a = random_image(20, 12, 3, 1, 0.0f, 1.0f), b = random_image(20, 12, 3, 2, 0.0f, 1.0f);
    MipTexture tex(a);
    tex.assign(b);
    const MipTexture fresh(b);
    ASSERT_EQ(tex.level_count(), fresh.level_count());
    for (int k = 0; k < tex.level_count(); ++k)
        for (std::size_t i = 0; i < fresh.level(k).values().size(); ++i)
            ASSERT_FLOAT_EQ(tex.level(k).values()[i], fresh.level(k).values()[i]) << "level " << k;
}

// The banded scatter (the trainer runs one band per thread) must give the same bits as add() in
// one pass, for any band count, since each texel still gets its sums in the taps' order.
TEST(TextureGradient, BandedScatterGivesTheSameBitsAsOnePass) {
    const MipTexture tex(random_image(37, 29, 4, 3, 0.0f, 1.0f));
    const std::vector<Lookup> lookups = random_lookups(3000, 17);
    std::vector<float> g(lookups.size() * 4);
    Rng rng(23);
    for (float& v : g) v = rng.uniform() * 2.f - 1.f;
    std::vector<TrilinearTaps> taps(lookups.size());
    for (std::size_t k = 0; k < lookups.size(); ++k) tex.taps(lookups[k].uv, lookups[k].lod, -1, taps[k]);
    MipGradient one_pass;
    one_pass.reset(tex);
    for (std::size_t k = 0; k < lookups.size(); ++k) one_pass.add(taps[k], &g[4 * k]);
    for (int count : {1, 2, 3, 8}) {
        MipGradient banded;
        banded.reset(tex);
        const MipGradient::Bands bands = banded.bands(count);
        for (int band = count - 1; band >= 0; --band)  // any band order: the bands are disjoint
            for (std::size_t k = 0; k < lookups.size(); ++k) banded.add_band(taps[k], &g[4 * k], bands, band);
        for (int level = 0; level < tex.level_count(); ++level) {
            const ImageValues& a = one_pass.level(level).values();
            const ImageValues& b = banded.level(level).values();
            ASSERT_EQ(a.size(), b.size());
            std::size_t differing = 0;
            for (std::size_t i = 0; i < a.size(); ++i) differing += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
            EXPECT_EQ(differing, 0u) << count << " bands, level " << level;
        }
    }
}

// The learned maps are composed into a texture's own level 0 and its mips rebuilt in place
// (LearnedMaps::update), and the trainer's targets are moved into their textures: both must give
// the very pyramid a texture built from a copy of the image gives.
TEST(TextureGradient, MovedImageAndInPlaceRebuildGiveTheSamePyramid) {
    const Image a = random_image(21, 13, 3, 4, 0.0f, 1.0f), b = random_image(21, 13, 3, 5, 0.0f, 1.0f);
    const MipTexture fresh(b);
    MipTexture moved(Image{b});
    MipTexture edited(a);
    edited.base_level() = b;
    edited.rebuild_levels();
    for (const MipTexture* tex : {&moved, &edited}) {
        ASSERT_EQ(tex->level_count(), fresh.level_count());
        for (int k = 0; k < fresh.level_count(); ++k)
            ASSERT_EQ(0, std::memcmp(tex->level(k).data(), fresh.level(k).data(),
                                     fresh.level(k).values().size() * sizeof(float)))
                << "level " << k;
    }
}
