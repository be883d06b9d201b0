#pragma once
// Images for tests of image operations: seeded random content and the inner product that
// adjoint tests compare (<A x, y> = <x, A^T y>).
#include <tdf/core/image.h>

#include <cstdint>

namespace tdf::test {

/// w x h x c values drawn uniformly from [lo, hi) by Rng(seed).
Image random_image(int w, int h, int c, std::uint64_t seed, float lo = -1.0f, float hi = 1.0f);

/// Sum of the products of corresponding values, in double (sizes must match).
double inner_product(const Image& a, const Image& b);

}  // namespace tdf::test
