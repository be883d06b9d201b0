#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/loss/image_loss.h>
#include <tdf/loss/tactile_loss.h>

#include <cstring>

#include "common/gradcheck.h"

using namespace tdf;
using test::check_gradient;
using test::random_values;

namespace {

// Analytic gradient of a loss over float inputs, via its `grad` output with weight 1.
template <typename Loss>
std::vector<float> analytic(const std::vector<float>& pred, Loss&& loss) {
    std::vector<float> grad(pred.size(), 0.0f);
    loss(pred, grad.data());
    return grad;
}

const Vec3f* as_vec3(const std::vector<float>& v) { return reinterpret_cast<const Vec3f*>(v.data()); }
Vec3f* as_vec3(float* v) { return reinterpret_cast<Vec3f*>(v); }

}  // namespace

TEST(ImageLoss, MseAndL1ValuesAndGradients) {
    const auto pred = random_values(300, 0, 1, 1), target = random_values(300, 0, 1, 2);
    auto mse = [&](const std::vector<float>& p, float* g) {
        return mse_loss(p.data(), target.data(), p.size(), g);
    };
    auto l1 = [&](const std::vector<float>& p, float* g) {
        return l1_loss(p.data(), target.data(), p.size(), g);
    };
    double expected_mse = 0, expected_l1 = 0;
    for (std::size_t i = 0; i < 300; ++i) {
        expected_mse += (double(pred[i]) - target[i]) * (double(pred[i]) - target[i]) / 300;
        expected_l1 += std::abs(double(pred[i]) - target[i]) / 300;
    }
    EXPECT_NEAR(mse(pred, nullptr), expected_mse, 1e-12);
    EXPECT_NEAR(l1(pred, nullptr), expected_l1, 1e-12);
    EXPECT_TRUE(check_gradient(
        [&](const std::vector<float>& p) { return mse(p, nullptr); }, pred, analytic(pred, mse)));
    // L1 is piecewise linear: a small step never crosses a kink for these random values.
    test::GradCheckConfig small;
    small.step = 1e-5;
    EXPECT_TRUE(check_gradient(
        [&](const std::vector<float>& p) { return l1(p, nullptr); }, pred, analytic(pred, l1), {}, small));
    // Gradients accumulate with the weight.
    std::vector<float> g(300, 1.0f);
    mse_loss(pred.data(), target.data(), 300, g.data(), 0.5f);
    const auto unit = analytic(pred, mse);
    EXPECT_FLOAT_EQ(g[7], 1.0f + 0.5f * unit[7]);
}

TEST(ImageLoss, MeanColourMseMatchesDefinitionAndGradient) {
    const ImageBatchShape shape{2, 5, 4, 3};
    const auto pred = random_values(shape.values(), 0, 1, 3), target = random_values(shape.values(), 0, 1, 4);
    auto loss = [&](const std::vector<float>& p, float* g) {
        return mean_colour_mse_loss(p.data(), target.data(), shape, g);
    };
    double expected = 0;
    for (int img = 0; img < 2; ++img)
        for (int c = 0; c < 3; ++c) {
            double d = 0;
            for (int k = 0; k < 20; ++k)
                d += double(pred[std::size_t((img * 20 + k) * 3 + c)]) -
                     target[std::size_t((img * 20 + k) * 3 + c)];
            expected += (d / 20) * (d / 20) / 6;
        }
    EXPECT_NEAR(loss(pred, nullptr), expected, 1e-12);
    test::GradCheckConfig config;
    config.abs_floor = 1e-4;
    EXPECT_TRUE(check_gradient([&](const std::vector<float>& p) { return loss(p, nullptr); },
                               pred,
                               analytic(pred, loss),
                               {},
                               config));
}

TEST(ImageLoss, CosineLossMatchesTorchSemantics) {
    // Identical vectors: loss 0; opposite: 2; zero vectors count with cos 0.
    const std::vector<Vec3f> a = {{1, 0, 0}, {0, 2, 0}}, b = {{3, 0, 0}, {0, -1, 0}};
    EXPECT_NEAR(cosine_loss(a.data(), a.data(), 2), 0.0, 1e-7);
    EXPECT_NEAR(cosine_loss(a.data(), b.data(), 2), 1.0, 1e-7);  // cos 1 and -1
    const std::vector<Vec3f> z = {{0, 0, 0}, {0, 0, 0}};
    EXPECT_NEAR(cosine_loss(z.data(), z.data(), 2), 1.0, 1e-12);
    std::vector<Vec3f> g(2);
    cosine_loss(z.data(), z.data(), 2, g.data());
    EXPECT_EQ(length(g[0]), 0.0f);  // background: no gradient
    EXPECT_FLOAT_EQ(cosine_similarity({1, 1, 0}, {1, 0, 0}), 1.0f / std::sqrt(2.0f));
}

TEST(ImageLoss, CosineAndMaskedCosineGradients) {
    const std::size_t n = 50;
    auto pred = random_values(3 * n, -1, 1, 5);
    const auto target = random_values(3 * n, -1, 1, 6);
    std::vector<float> mask(n);
    for (std::size_t i = 0; i < n; ++i) mask[i] = i % 3 == 0 ? 0.0f : (i % 3 == 1 ? 1.0f : 0.5f);
    auto cos = [&](const std::vector<float>& p, float* g) {
        return cosine_loss(as_vec3(p), as_vec3(target), n, g ? as_vec3(g) : nullptr);
    };
    auto masked = [&](const std::vector<float>& p, float* g) {
        return masked_cosine_loss(as_vec3(p), as_vec3(target), mask.data(), n, g ? as_vec3(g) : nullptr);
    };
    EXPECT_TRUE(check_gradient(
        [&](const std::vector<float>& p) { return cos(p, nullptr); }, pred, analytic(pred, cos)));
    EXPECT_TRUE(check_gradient(
        [&](const std::vector<float>& p) { return masked(p, nullptr); }, pred, analytic(pred, masked)));
    // Masked-out vectors get no gradient; the masked loss counts them with cos 0.
    const auto g = analytic(pred, masked);
    EXPECT_EQ(g[0], 0.0f);
    EXPECT_GT(masked(pred, nullptr), 0.3);
}

TEST(ImageLoss, SsimIsOneForIdenticalImagesAndGradientMatches) {
    const ImageBatchShape shape{2, 13, 9, 3};
    const auto target = random_values(shape.values(), 0, 1, 7);
    auto pred = target;
    const auto noise = random_values(shape.values(), -0.2f, 0.2f, 8);
    auto loss = [&](const std::vector<float>& p, float* g) {
        return ssim_loss(p.data(), target.data(), shape, g);
    };
    EXPECT_NEAR(loss(pred, nullptr), 0.0, 1e-6);
    for (std::size_t i = 0; i < pred.size(); ++i) pred[i] += noise[i];
    const double value = loss(pred, nullptr);
    EXPECT_GT(value, 0.05);
    EXPECT_LT(value, 1.0);
    std::vector<std::size_t> indices;
    for (std::size_t i = 0; i < pred.size(); i += 7) indices.push_back(i);
    test::GradCheckConfig config;
    config.abs_floor = 1e-4;
    EXPECT_TRUE(check_gradient([&](const std::vector<float>& p) { return loss(p, nullptr); },
                               pred,
                               analytic(pred, loss),
                               indices,
                               config));
}

TEST(TactileLoss, GuidanceMetricsAndGradients) {
    const std::size_t n = 40;
    const auto pred = random_values(3 * n, -1, 1, 9), refined = random_values(3 * n, -1, 1, 10);
    for (const auto metric : {TactileGuidanceMetric::Mse, TactileGuidanceMetric::Cosine}) {
        auto loss = [&](const std::vector<float>& p, float* g) {
            return tactile_guidance_loss(metric, as_vec3(p), as_vec3(refined), n, g ? as_vec3(g) : nullptr);
        };
        EXPECT_TRUE(check_gradient(
            [&](const std::vector<float>& p) { return loss(p, nullptr); }, pred, analytic(pred, loss)));
    }
    EXPECT_NEAR(tactile_guidance_loss(TactileGuidanceMetric::Mse, as_vec3(pred), as_vec3(refined), n),
                mse_loss(pred.data(), refined.data(), 3 * n),
                0.0);
    EXPECT_EQ(parse_tactile_guidance_metric("cosine", "k"), TactileGuidanceMetric::Cosine);
    EXPECT_THROW(parse_tactile_guidance_metric("l2", "k"), Error);
}

TEST(ImageLoss, ValuesAndGradientsAreBitIdenticalOnOneAndTwoThreads) {
    const ImageBatchShape shape{2, 130, 70, 3};
    const auto pred = random_values(shape.values(), 0, 1, 11),
               target = random_values(shape.values(), 0, 1, 12);
    auto run = [&](int threads, std::vector<float>& g) {
        ThreadLimit limit(threads);
        g.assign(pred.size(), 0.0f);
        return mse_loss(pred.data(), target.data(), pred.size(), g.data()) +
               ssim_loss(pred.data(), target.data(), shape, g.data()) +
               mean_colour_mse_loss(pred.data(), target.data(), shape, g.data());
    };
    std::vector<float> g1, g2;
    const double v1 = run(1, g1), v2 = run(2, g2);
    EXPECT_EQ(v1, v2);
    EXPECT_EQ(std::memcmp(g1.data(), g2.data(), g1.size() * sizeof(float)), 0);
}
