#include "common/gradcheck.h"

#include <tdf/core/rng.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace tdf::test {

::testing::AssertionResult check_gradient(const ScalarFunction& f, std::vector<float> x,
                                          const std::vector<float>& analytic,
                                          const std::vector<std::size_t>& indices,
                                          const GradCheckConfig& config) {
    if (analytic.size() != x.size())
        return ::testing::AssertionFailure()
               << "analytic gradient has " << analytic.size() << " values for " << x.size() << " inputs";
    std::vector<std::size_t> checked = indices;
    if (checked.empty())
        for (std::size_t i = 0; i < x.size(); ++i) checked.push_back(i);
    double worst = -1, sum = 0;
    std::size_t worst_index = 0;
    double worst_analytic = 0, worst_numeric = 0;
    for (const std::size_t i : checked) {
        const float original = x[i];
        const float plus = float(double(original) + config.step);
        const float minus = float(double(original) - config.step);
        x[i] = plus;
        const double f_plus = f(x);
        x[i] = minus;
        const double f_minus = f(x);
        x[i] = original;
        const double numeric = (f_plus - f_minus) / (double(plus) - double(minus));
        const double error =
            std::abs(double(analytic[i]) - numeric) / std::max(std::abs(numeric), config.abs_floor);
        sum += error;
        if (error > worst) {
            worst = error;
            worst_index = i;
            worst_analytic = analytic[i];
            worst_numeric = numeric;
        }
    }
    const double mean = checked.empty() ? 0.0 : sum / double(checked.size());
    if (worst <= config.max_rel_tol && mean <= config.mean_rel_tol)
        return ::testing::AssertionSuccess() << "max rel error " << worst << ", mean " << mean;
    std::ostringstream s;
    s << "gradient check over " << checked.size() << " inputs (step " << config.step << "): max rel error "
      << worst << " (threshold " << config.max_rel_tol << ", excess " << worst - config.max_rel_tol
      << ") at input " << worst_index << ": analytic " << worst_analytic << " vs numeric " << worst_numeric
      << "; mean rel error " << mean << " (threshold " << config.mean_rel_tol << ")";
    return ::testing::AssertionFailure() << s.str();
}

std::vector<float> random_values(std::size_t count, float lo, float hi, std::uint64_t seed) {
    Rng rng(seed);
    std::vector<float> values(count);
    for (float& v : values) v = rng.uniform(lo, hi);
    return values;
}

}  // namespace tdf::test
