#pragma once
// FFTW helpers shared by the tactile sources. FFTW's planner is not thread-safe (its execute
// functions are), so every plan is made and destroyed under one lock. Plans use FFTW_ESTIMATE:
// the algorithm, and with it every rounding, must not depend on timing measurements, or
// results would differ between runs.
#include <fftw3.h>

#include <cstddef>
#include <memory>
#include <mutex>

namespace tdf::fftw {

std::mutex& planner_mutex();

struct PlanDeleter {
    void operator()(fftw_plan_s* plan) const {
        std::lock_guard<std::mutex> lock(planner_mutex());
        fftw_destroy_plan(plan);
    }
};
using Plan = std::unique_ptr<fftw_plan_s, PlanDeleter>;

struct Free {
    void operator()(void* p) const { fftw_free(p); }
};
/// SIMD-aligned buffers, so that new-array execution (fftw_execute_dft_r2c etc.) from worker
/// threads sees the same alignment as the planning arrays.
using RealBuffer = std::unique_ptr<double[], Free>;
using ComplexBuffer = std::unique_ptr<fftw_complex[], Free>;

inline RealBuffer alloc_real(std::size_t n) { return RealBuffer(fftw_alloc_real(n)); }
inline ComplexBuffer alloc_complex(std::size_t n) { return ComplexBuffer(fftw_alloc_complex(n)); }

/// 2-D real-to-real transform of a height x width row-major array, in place.
Plan plan_r2r(int width, int height, double* data, fftw_r2r_kind kind);
/// 2-D real-to-complex (height x (width/2+1) outputs) and its inverse, out of place.
Plan plan_r2c(int width, int height, double* in, fftw_complex* out);
Plan plan_c2r(int width, int height, fftw_complex* in, double* out);

}  // namespace tdf::fftw
