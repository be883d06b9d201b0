#include "common/test_images.h"

#include <tdf/core/rng.h>

#include <gtest/gtest.h>

namespace tdf::test {

Image random_image(int w, int h, int c, std::uint64_t seed, float lo, float hi) {
    Image image(w, h, c);
    Rng rng(seed);
    for (float& v : image.values()) v = rng.uniform(lo, hi);
    return image;
}

double inner_product(const Image& a, const Image& b) {
    EXPECT_EQ(a.values().size(), b.values().size());
    double sum = 0;
    for (std::size_t i = 0; i < a.values().size() && i < b.values().size(); ++i)
        sum += double(a.values()[i]) * double(b.values()[i]);
    return sum;
}

}  // namespace tdf::test
