// The N-logit part-label head (issue 14): softmax cross-entropy and the head's gradient against
// finite differences, for several part counts, and the same gradient on any thread count.
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/train/part_label_head.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace tdf;

TEST(PartLabelHead, SoftmaxCrossEntropyGradientMatchesFiniteDifferences) {
    Rng rng(11);
    for (int parts : {2, 3, 5, 9}) {
        std::vector<float> z(static_cast<std::size_t>(parts)), d(z.size());
        for (float& v : z) v = rng.uniform(-4.0f, 4.0f);
        const int label = parts / 2;
        const double loss = softmax_cross_entropy(z.data(), parts, label, 0.5f, d.data());
        // -log p_label with p the softmax, computed the plain way.
        double sum = 0;
        for (float v : z) sum += std::exp(double(v));
        EXPECT_NEAR(loss, -std::log(std::exp(double(z[std::size_t(label)])) / sum), 1e-5);
        double d_sum = 0;
        for (int c = 0; c < parts; ++c) {
            std::vector<float> plus = z, minus = z;
            const float h = 1e-2f;
            plus[std::size_t(c)] += h;
            minus[std::size_t(c)] -= h;
            const double numeric = (softmax_cross_entropy(plus.data(), parts, label, 1.0f, nullptr) -
                                    softmax_cross_entropy(minus.data(), parts, label, 1.0f, nullptr)) /
                                   (2.0 * double(h));
            EXPECT_NEAR(double(d[std::size_t(c)]), 0.5 * numeric, 2e-4) << parts << " parts, logit " << c;
            d_sum += double(d[std::size_t(c)]);
        }
        EXPECT_NEAR(d_sum, 0.0, 1e-6);  // softmax - onehot sums to 0
    }
    // Huge logits stay finite (the max is subtracted).
    const float big[3] = {1000.0f, -1000.0f, 999.0f};
    float d[3];
    EXPECT_NEAR(softmax_cross_entropy(big, 3, 2, 1.0f, d), 1.0 + std::log1p(std::exp(-1.0)), 1e-4);
    EXPECT_TRUE(std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2]));
}

namespace {

struct HeadFixture {
    TextureField field;
    std::vector<Vec3f> points;
    std::vector<int> labels;
    explicit HeadFixture(int parts)
        : field(
              [] {
                  FieldConfig c;
                  c.grid.levels = 4;
                  c.grid.log2_table_size = 8;
                  return c;
              }(),
              FieldDomain{{-1, -1, -1}, {1, 1, 1}}, 5) {
        Rng rng(7);
        // Grid entries large enough that the encoding (and its gradient) matters.
        for (std::size_t i = 0; i < field.grid().parameter_count(); ++i) field.parameters()[i] = rng.uniform(-1.0f, 1.0f);
        for (int i = 0; i < 3000; ++i) {
            points.push_back({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
            labels.push_back(i % 7 == 0 ? -1 : rng.uniform_int(0, parts));
        }
    }
};

}  // namespace

TEST(PartLabelHead, LossGradientMatchesFiniteDifferencesForAnyPartCount) {
    for (int parts : {2, 4, 6}) {
        HeadFixture f(parts);
        PartLabelHead head(parts, f.field.feature_count(), 3);
        const auto loss = [&] {
            std::vector<float> unused;
            return head.loss_and_gradient(f.field, f.points.data(), f.labels.data(), f.points.size(), 1.5f, unused,
                                          nullptr);
        };
        std::vector<float> head_gradient, field_gradient(f.field.parameter_count(), 0.0f);
        std::size_t labelled = 0;
        head.loss_and_gradient(f.field, f.points.data(), f.labels.data(), f.points.size(), 1.5f, head_gradient,
                               &field_gradient, &labelled);
        EXPECT_GT(labelled, 2000u);
        EXPECT_LT(labelled, f.points.size());
        const auto check = [&](std::vector<float>& values, std::size_t index, float analytic, const char* what) {
            const float saved = values[index];
            const float h = 1e-2f;
            values[index] = saved + h;
            const double up = loss();
            values[index] = saved - h;
            const double down = loss();
            values[index] = saved;
            const double numeric = (up - down) / (2.0 * double(h));
            EXPECT_NEAR(double(analytic), numeric, 2e-3 + 2e-2 * std::fabs(numeric))
                << parts << " parts, " << what << " " << index;
        };
        // Every head parameter, and the grid entries with the largest gradients (the ones the
        // points touch).
        for (std::size_t j = 0; j < head.parameters().size(); j += 3) check(head.parameters(), j, head_gradient[j], "head");
        std::vector<std::size_t> order(f.field.grid().parameter_count());
        for (std::size_t j = 0; j < order.size(); ++j) order[j] = j;
        std::partial_sort(order.begin(), order.begin() + 12, order.end(), [&](std::size_t a, std::size_t b) {
            return std::fabs(field_gradient[a]) > std::fabs(field_gradient[b]);
        });
        EXPECT_GT(std::fabs(field_gradient[order[0]]), 1e-4f);
        for (int j = 0; j < 12; ++j)
            check(f.field.parameters(), order[std::size_t(j)], field_gradient[order[std::size_t(j)]], "grid");
        // The heads (not the grid) are the field's business: untouched.
        for (std::size_t j = f.field.grid().parameter_count(); j < field_gradient.size(); ++j)
            ASSERT_EQ(field_gradient[j], 0.0f);
    }
}

TEST(PartLabelHead, SameGradientOnOneAndTwoThreads) {
    HeadFixture f(5);
    PartLabelHead head(5, f.field.feature_count(), 3);
    const auto run = [&](int threads) {
        ThreadLimit limit(threads);
        std::vector<float> head_gradient, field_gradient(f.field.parameter_count(), 0.0f);
        const double loss = head.loss_and_gradient(f.field, f.points.data(), f.labels.data(), f.points.size(), 1.0f,
                                                   head_gradient, &field_gradient);
        head_gradient.push_back(float(loss));
        head_gradient.insert(head_gradient.end(), field_gradient.begin(), field_gradient.end());
        return head_gradient;
    };
    EXPECT_EQ(run(1), run(2));
}

TEST(PartLabelHead, NoPartIsRefused) {
    EXPECT_THROW(PartLabelHead(0, 32, 0), Error);
    EXPECT_NO_THROW(PartLabelHead(1, 32, 0));  // one part: the whole surface (its loss is 0)
}
