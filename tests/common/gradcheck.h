#pragma once
// Finite-difference gradient checks for float code (STYLE 8.20). The scalar function is
// evaluated by the float code under test and summed in double; central differences use the
// step actually representable in float, so the comparison measures the analytic gradient and
// not the rounding of the perturbation.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace tdf::test {

struct GradCheckConfig {
    double step = 1e-3;          ///< central-difference step added to one float input
    double max_rel_tol = 2e-2;   ///< largest allowed |analytic - fd| / max(|fd|, abs_floor)
    double mean_rel_tol = 5e-3;  ///< allowed mean of that error over the checked inputs
    double abs_floor = 1e-3;     ///< below this magnitude errors count as absolute
};

/// Scalar function of a float vector, evaluated by the code under test.
using ScalarFunction = std::function<double(const std::vector<float>&)>;

/// Compares `analytic[i]` with the central difference of `f` at `x` for every i in `indices`
/// (all inputs when empty). The failure message lists the thresholds, the worst input with its
/// analytic and numeric values, and the excess over the threshold.
::testing::AssertionResult check_gradient(const ScalarFunction& f, std::vector<float> x,
                                          const std::vector<float>& analytic,
                                          const std::vector<std::size_t>& indices = {},
                                          const GradCheckConfig& config = {});

/// Fixed pseudo-random values in [lo, hi) (a test's weights for sum_i c_i * output_i).
std::vector<float> random_values(std::size_t count, float lo, float hi, std::uint64_t seed);

}  // namespace tdf::test
