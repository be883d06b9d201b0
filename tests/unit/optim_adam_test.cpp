#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/optim/adam.h>

#include <cmath>
#include <cstring>

using namespace tdf;

TEST(Adam, FirstStepMovesEveryParameterByLearningRate) {
    Adam adam(3);
    std::vector<float> p = {1.0f, -2.0f, 0.5f};
    adam.step(p, {0.3f, -4.0f, 1e-3f});
    // Step 1: m_hat = g, v_hat = g^2, so the update is lr * g / (|g| + eps) = lr * sign(g).
    EXPECT_NEAR(p[0], 1.0f - 0.01f, 1e-6f);
    EXPECT_NEAR(p[1], -2.0f + 0.01f, 1e-6f);
    EXPECT_NEAR(p[2], 0.5f - 0.01f, 1e-6f);
}

namespace {
std::vector<float> gradient_at(const std::vector<float>& p, int step) {
    // A deterministic, step-dependent gradient (quadratic bowl plus a wobble).
    std::vector<float> g(p.size());
    for (std::size_t i = 0; i < p.size(); ++i)
        g[i] = 2.0f * (p[i] - float(i % 7)) + 0.1f * float((step + int(i)) % 3);
    return g;
}
}  // namespace

TEST(Adam, SaveRestoreContinuesBitForBit) {
    const std::size_t n = 50000;  // several parallel chunks
    std::vector<float> uninterrupted(n, 0.5f);
    Adam a(n);
    for (int s = 0; s < 10; ++s) a.step(uninterrupted, gradient_at(uninterrupted, s));

    std::vector<float> resumed(n, 0.5f);
    std::string blob;
    {
        Adam b(n);
        for (int s = 0; s < 4; ++s) b.step(resumed, gradient_at(resumed, s));
        blob = b.state().to_bytes();
    }
    Adam c(n);
    c.restore(AdamState::from_bytes(blob, "blob"));
    EXPECT_EQ(c.state().step, 4);
    for (int s = 4; s < 10; ++s) c.step(resumed, gradient_at(resumed, s));
    EXPECT_EQ(std::memcmp(uninterrupted.data(), resumed.data(), n * sizeof(float)), 0);
    EXPECT_TRUE(a.state() == c.state());
}

TEST(Adam, MatchesTorchFormulaOverSeveralSteps) {
    // Scalar reference computed in double with torch's formula.
    Adam adam(1);
    std::vector<float> p = {1.0f};
    double m = 0, v = 0, x = 1.0;
    for (int s = 1; s <= 20; ++s) {
        const float g = 0.3f * float(s % 4) - 0.4f;
        adam.step(p, {g});
        m = 0.9 * m + 0.1 * g;
        v = 0.999 * v + 0.001 * double(g) * g;
        x -= 0.01 / (1 - std::pow(0.9, s)) * m / (std::sqrt(v) / std::sqrt(1 - std::pow(0.999, s)) + 1e-8);
        EXPECT_NEAR(p[0], x, 1e-6) << "step " << s;
    }
}

TEST(Adam, CorruptStateIsRejected) {
    Adam adam(10);
    std::vector<float> p(10, 1.0f);
    adam.step(p, std::vector<float>(10, 0.5f));
    const std::string blob = adam.state().to_bytes();
    EXPECT_THROW(AdamState::from_bytes(blob.substr(0, blob.size() - 3), "cut"), Error);
    EXPECT_THROW(AdamState::from_bytes("garbage", "junk"), Error);
    std::string bad = blob;
    bad[0] = 'X';
    EXPECT_THROW(AdamState::from_bytes(bad, "magic"), Error);
    EXPECT_THROW(Adam(11).restore(adam.state()), Error);
}
