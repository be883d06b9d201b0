#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/field/texture_field.h>

#include <cstring>

#include "common/gradcheck.h"

using namespace tdf;

namespace {

const FieldDomain kDomain{{-1.0f, -0.5f, -0.8f}, {1.0f, 0.7f, 0.9f}};

std::vector<Vec3f> random_points(std::size_t n, std::uint64_t seed, const FieldDomain& d = kDomain) {
    Rng rng(seed);
    std::vector<Vec3f> points(n);
    for (Vec3f& p : points)
        p = {rng.uniform(d.lower.x, d.upper.x),
             rng.uniform(d.lower.y, d.upper.y),
             rng.uniform(d.lower.z, d.upper.z)};
    return points;
}

std::vector<FieldOutputGrads> random_grads(std::size_t n, std::uint64_t seed) {
    Rng rng(seed);
    std::vector<FieldOutputGrads> grads(n);
    for (FieldOutputGrads& g : grads) {
        g.d_albedo = {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
        g.d_normal = {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
        g.d_label[0] = rng.uniform(-1, 1);
        g.d_label[1] = rng.uniform(-1, 1);
    }
    return grads;
}

// L = sum_i <grads_i, outputs_i>, so dL/dparams is exactly what backward() accumulates.
double weighted_outputs(const TextureField& field, const std::vector<Vec3f>& points,
                        const std::vector<FieldOutputGrads>& grads) {
    std::vector<FieldOutputs> out(points.size());
    field.evaluate(points.data(), points.size(), out.data());
    double sum = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            sum += double(grads[i].d_albedo[k]) * out[i].albedo[k];
            sum += double(grads[i].d_normal[k]) * out[i].normal[k];
        }
        for (int k = 0; k < 2; ++k) sum += double(grads[i].d_label[k]) * out[i].label[k];
    }
    return sum;
}

// Finite differences (step 1e-2) of weighted_outputs against `gradient` at `indices`.
bool gradient_matches_finite_differences(TextureField& field, const std::vector<Vec3f>& points,
                                         const std::vector<FieldOutputGrads>& grads, const std::vector<float>& gradient,
                                         const std::vector<std::size_t>& indices) {
    test::GradCheckConfig check;
    check.step = 1e-2;
    return test::check_gradient(
        [&](const std::vector<float>& p) {
            field.parameters() = p;
            return weighted_outputs(field, points, grads);
        },
        field.parameters(),
        gradient,
        indices,
        check);
}

}  // namespace

TEST(TextureField, ParameterLayoutMatchesReference) {
    FieldConfig config;
    const TextureField field(config, kDomain, 1);
    EXPECT_EQ(field.parameter_count(), 953344u + 264u);
    EXPECT_EQ(field.parameter_block("grid").count, 953344u);
    EXPECT_EQ(field.parameter_block("albedo.weight").count, 96u);
    EXPECT_EQ(field.parameter_block("albedo.bias").offset, 953344u + 96u);
    EXPECT_EQ(field.parameter_block("label.bias").offset + 2, field.parameter_count());
    EXPECT_THROW(field.parameter_block("nope"), Error);
    TextureField copy(config, kDomain, 2);
    copy.set_parameters(field.parameters(), "test");
    EXPECT_EQ(copy.parameters(), field.parameters());
    EXPECT_THROW(copy.set_parameters(std::vector<float>(10), "short.ckpt"), Error);
    // Init ranges: grid U[-1e-4, 1e-4], heads U(-1/sqrt(32), 1/sqrt(32)).
    const auto& p = field.parameters();
    float grid_max = 0, head_max = 0;
    for (std::size_t i = 0; i < 953344u; ++i) grid_max = std::max(grid_max, std::abs(p[i]));
    for (std::size_t i = 953344u; i < p.size(); ++i) head_max = std::max(head_max, std::abs(p[i]));
    EXPECT_LE(grid_max, 1e-4f);
    EXPECT_GT(grid_max, 0.9e-4f);
    EXPECT_LE(head_max, 1.0f / std::sqrt(32.0f));
    EXPECT_GT(head_max, 0.15f);
}

TEST(TextureField, OutputsAreInRangeAndSeeded) {
    FieldConfig config;
    config.labels = true;
    const TextureField a(config, kDomain, 7), b(config, kDomain, 7), c(config, kDomain, 8);
    const auto points = random_points(500, 3);
    std::vector<FieldOutputs> oa(500), ob(500), oc(500);
    a.evaluate(points.data(), 500, oa.data());
    b.evaluate(points.data(), 500, ob.data());
    c.evaluate(points.data(), 500, oc.data());
    EXPECT_EQ(std::memcmp(oa.data(), ob.data(), sizeof(FieldOutputs) * 500), 0);
    EXPECT_NE(std::memcmp(oa.data(), oc.data(), sizeof(FieldOutputs) * 500), 0);
    for (const FieldOutputs& o : oa) {
        for (int k = 0; k < 3; ++k) {
            EXPECT_GT(o.albedo[k], 0.0f);
            EXPECT_LT(o.albedo[k], 1.0f);
        }
        EXPECT_NEAR(length(o.normal), 1.0f, 1e-5f);
        EXPECT_GE(o.normal.z, 0.0f);
    }
}

TEST(TextureField, BoundingBoxInputMapsIntoUnitCube) {
    FieldConfig config;
    config.margin = 0.1f;
    const TextureField field(config, kDomain, 1);
    // Longest side 2 (x), padded to 2.4, centred on the box centre.
    const Vec3f lo = field.to_grid(kDomain.lower), hi = field.to_grid(kDomain.upper);
    EXPECT_NEAR(lo.x, 0.2f / 2.4f, 1e-6f);
    EXPECT_NEAR(hi.x, 2.2f / 2.4f, 1e-6f);
    EXPECT_NEAR(0.5f * (lo.y + hi.y), 0.5f, 1e-6f);
    EXPECT_NEAR(hi.z - lo.z, 1.7f / 2.4f, 1e-6f);
    config.input = FieldInput::RawWrapped;
    const TextureField raw(config, kDomain, 1);
    EXPECT_EQ(raw.to_grid(Vec3f(-0.3f, 0.2f, 5.0f)).x, -0.3f);
    EXPECT_THROW(TextureField(FieldConfig{}, FieldDomain{{0, 0, 0}, {0, 0, 0}}, 1), Error);
}

TEST(TextureField, BackwardMatchesFiniteDifferencesForHeads) {
    FieldConfig config;
    config.labels = true;
    TextureField field(config, kDomain, 11);
    const auto points = random_points(24, 5);
    const auto grads = random_grads(24, 6);
    std::vector<float> gradient;
    field.backward(points.data(), grads.data(), points.size(), gradient);
    const std::size_t heads = field.parameter_block("albedo.weight").offset;
    std::vector<std::size_t> indices;
    for (std::size_t i = heads; i < field.parameter_count(); ++i) indices.push_back(i);
    EXPECT_TRUE(gradient_matches_finite_differences(field, points, grads, gradient, indices));
}

TEST(TextureField, BackwardMatchesFiniteDifferencesForDenseAndHashedLevels) {
    FieldConfig config;
    config.input = FieldInput::RawWrapped;  // negative coordinates exercise the wrap-around
    TextureField field(config, kDomain, 12);
    // Larger grid values make the heads' non-linearity visible to the check.
    for (std::size_t i = 0; i < field.parameter_block("grid").count; ++i) field.parameters()[i] *= 1000.0f;
    const auto points = random_points(6, 9);
    const auto grads = random_grads(6, 10);
    std::vector<float> gradient;
    field.backward(points.data(), grads.data(), points.size(), gradient);
    // Entries touched by the points on dense levels 0-1 and hashed levels 2, 7, 15.
    std::vector<std::size_t> indices;
    for (const int level : {0, 1, 2, 7, 15}) {
        const HashGridLevel& l = field.grid().levels()[std::size_t(level)];
        std::size_t found = 0;
        for (std::size_t e = l.offset; e < l.offset + l.table_size && found < 12; ++e)
            for (int f = 0; f < 2; ++f)
                if (gradient[e * 2 + std::size_t(f)] != 0.0f)
                    indices.push_back(e * 2 + std::size_t(f)), ++found;
        EXPECT_GE(found, 8u) << "level " << level;
        indices.push_back(std::size_t(l.offset) * 2 + 1);  // most likely untouched: gradient 0
    }
    EXPECT_TRUE(gradient_matches_finite_differences(field, points, grads, gradient, indices));
}

TEST(TextureField, BackwardIsBitIdenticalOnOneAndTwoThreads) {
    FieldConfig config;
    config.labels = true;
    const TextureField field(config, kDomain, 13);
    // 70,000 points: several fixed chunks and three backward blocks.
    const auto points = random_points(70000, 14);
    const auto grads = random_grads(70000, 15);
    std::vector<float> one, two;
    {
        ThreadLimit limit(1);
        field.backward(points.data(), grads.data(), points.size(), one);
    }
    {
        ThreadLimit limit(2);
        field.backward(points.data(), grads.data(), points.size(), two);
    }
    ASSERT_EQ(one.size(), two.size());
    EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(float)), 0);
    std::size_t nonzero = 0;
    for (const float g : one) nonzero += g != 0.0f;
    EXPECT_GT(nonzero, 100000u);
    // backward() accumulates into an existing gradient: a second call doubles every value
    // (up to float rounding of sums with cancellation).
    field.backward(points.data(), grads.data(), points.size(), two);
    for (std::size_t i = 0; i < one.size(); i += 97)
        ASSERT_NEAR(two[i], 2.0f * one[i], 1e-3f * std::abs(one[i]) + 1e-8f) << i;
}

TEST(TextureField, CachedForwardGivesTheSameOutputsAndGradientBits) {
    FieldConfig config;
    config.labels = true;
    const TextureField field(config, kDomain, 21);
    // Not a multiple of the encode block, so the last cached block is partial.
    const std::size_t n = 20000;
    const auto points = random_points(n, 22);
    const auto grads = random_grads(n, 23);
    std::vector<FieldOutputs> plain(n), cached(n);
    field.evaluate(points.data(), n, plain.data());
    FieldCache cache;
    // A larger batch first: the cache is reused for a smaller one.
    const auto more = random_points(n + 5000, 24);
    std::vector<FieldOutputs> scratch(more.size());
    field.evaluate(more.data(), more.size(), scratch.data(), cache);
    field.evaluate(points.data(), n, cached.data(), cache);
    EXPECT_EQ(cache.point_count(), n);
    EXPECT_EQ(std::memcmp(plain.data(), cached.data(), n * sizeof(FieldOutputs)), 0);

    std::vector<float> recomputed, from_cache;
    field.backward(points.data(), grads.data(), n, recomputed);
    {
        ThreadLimit limit(1);
        field.backward(points.data(), grads.data(), n, from_cache, cache);
    }
    ASSERT_EQ(recomputed.size(), from_cache.size());
    EXPECT_EQ(std::memcmp(recomputed.data(), from_cache.data(), recomputed.size() * sizeof(float)), 0);

    // A cache of another point count is an internal error, not silent garbage.
    EXPECT_THROW(field.backward(points.data(), grads.data(), n - 1, from_cache, cache), Error);
    cache.clear();
    EXPECT_EQ(cache.point_count(), 0u);
}
