#pragma once
// FFTW helpers shared by the tactile sources. FFTW's planner is not thread-safe (its execute
// functions are), so every plan is made and destroyed under one lock. Plans use FFTW_ESTIMATE:
// the algorithm, and with it every rounding, must not depend on timing measurements, or
// results would differ between runs.
#include <fftw3.h>
#include <tdf/core/parallel.h>

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

/// Solves, in place, a width x height row-major system whose operator the 2-D DCT-II (reflecting
/// borders) diagonalises: forward REDFT10, each coefficient divided by eigenvalue(u, v), the
/// constant term (0, 0) set to 0 (the mean is free), inverse REDFT01. FFTW's pair is not
/// normalised: `data` ends as 4 width height times the solution. The one implementation of the
/// integrators with reflecting borders (integrate_gradients, integrate_normal_map's mirrored case).
template <class Eigenvalue>
void solve_in_cosine_basis(double* data, int width, int height, Eigenvalue&& eigenvalue) {
    {
        const Plan forward = plan_r2r(width, height, data, FFTW_REDFT10);
        fftw_execute(forward.get());
    }
    parallel_for(std::size_t(height), 16, [&](std::size_t v0, std::size_t v1) {
        for (int v = int(v0); v < int(v1); ++v)
            for (int u = 0; u < width; ++u) {
                double& value = data[std::size_t(v) * std::size_t(width) + std::size_t(u)];
                value = (u == 0 && v == 0) ? 0.0 : value / eigenvalue(u, v);
            }
    });
    const Plan inverse = plan_r2r(width, height, data, FFTW_REDFT01);
    fftw_execute(inverse.get());
}

}  // namespace tdf::fftw
