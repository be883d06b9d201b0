#include "fftw_plan_impl.h"

namespace tdf::fftw {

std::mutex& planner_mutex() {
    static std::mutex mutex;
    return mutex;
}

Plan plan_r2r(int width, int height, double* data, fftw_r2r_kind kind) {
    std::lock_guard<std::mutex> lock(planner_mutex());
    return Plan(fftw_plan_r2r_2d(height, width, data, data, kind, kind, FFTW_ESTIMATE));
}

Plan plan_r2c(int width, int height, double* in, fftw_complex* out) {
    std::lock_guard<std::mutex> lock(planner_mutex());
    return Plan(fftw_plan_dft_r2c_2d(height, width, in, out, FFTW_ESTIMATE));
}

Plan plan_c2r(int width, int height, fftw_complex* in, double* out) {
    std::lock_guard<std::mutex> lock(planner_mutex());
    return Plan(fftw_plan_dft_c2r_2d(height, width, in, out, FFTW_ESTIMATE));
}

}  // namespace tdf::fftw
