#include <tdf/tactile/height_export.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/tactile/ambient_occlusion.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/pipeline.h>

#include "fftw_plan_impl.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

namespace tdf {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Target slopes: normals_from_height gives n ~ (-(h[x+1] - h[x-1]) / 2, (h[y+1] - h[y-1]) / 2, 1)
// with y the row index, so Dx h = -nx / nz and Dy h = ny / nz (central differences).
inline double slope_x(const float* n) { return double(-n[0] / std::max(n[2], 0.1f)); }
inline double slope_y(const float* n) { return double(n[1] / std::max(n[2], 0.1f)); }

// The map wraps: H = (conj(Dx) Fx + conj(Dy) Fy) / (|Dx|^2 + |Dy|^2) with Dx = i sin(2 pi u / w),
// the least-squares heights for central differences; zero where they see nothing.
Image integrate_periodic(const Image& normals) {
    const int w = normals.width(), h = normals.height();
    const std::size_t n = std::size_t(w) * std::size_t(h), nc = std::size_t(h) * std::size_t(w / 2 + 1);
    const auto transformed_slope = [&](bool along_x) {
        fftw::RealBuffer d = fftw::alloc_real(n);
        parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t y = y0; y < y1; ++y)
                for (int x = 0; x < w; ++x) {
                    const float* p = normals.pixel(x, int(y));
                    d[y * std::size_t(w) + std::size_t(x)] = along_x ? slope_x(p) : slope_y(p);
                }
        });
        fftw::ComplexBuffer f = fftw::alloc_complex(nc);
        const fftw::Plan plan = fftw::plan_r2c(w, h, d.get(), f.get());
        fftw_execute(plan.get());
        return f;
    };
    const fftw::ComplexBuffer fx = transformed_slope(true);
    fftw::ComplexBuffer fy = transformed_slope(false);
    const int half = w / 2 + 1;
    parallel_for(std::size_t(h), 16, [&](std::size_t v0, std::size_t v1) {
        for (int v = int(v0); v < int(v1); ++v) {
            const double sv = std::sin(2.0 * kPi * v / h);
            for (int u = 0; u < half; ++u) {
                const double su = std::sin(2.0 * kPi * u / w);
                const double denominator = su * su + sv * sv;
                const std::size_t i = std::size_t(v) * std::size_t(half) + std::size_t(u);
                // conj(i s) (a + i b) = s b - i s a
                const double re = su * fx[i][1] + sv * fy[i][1], im = -(su * fx[i][0] + sv * fy[i][0]);
                const bool visible = denominator > 1e-12;
                fx[i][0] = visible ? re / denominator : 0.0;
                fx[i][1] = visible ? im / denominator : 0.0;
            }
        }
    });
    fy.reset();
    const fftw::RealBuffer heights = fftw::alloc_real(n);
    {
        const fftw::Plan inverse = fftw::plan_c2r(w, h, fx.get(), heights.get());
        fftw_execute(inverse.get());
    }
    Image height(w, h, 1);
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) mean += heights[i];
    mean /= double(n);
    const double normalisation = 1.0 / double(n);
    for (std::size_t i = 0; i < n; ++i) height.data()[i] = float((heights[i] - mean) * normalisation);
    return height;
}

// The map is mirrored to twice its size (even heights, odd slopes), and that periodic problem is
// solved on the even half alone: its right-hand side conj(D) g = D^T g is even, and the DCT-II
// basis cos(pi u (x + 1/2) / w) diagonalises D^T D with eigenvalue sin^2(pi u / w). One in-place
// array of w x h doubles instead of four complex spectra of the 2w x 2h mirror (a 4096^2 map:
// 134 MB, not 1.6 GB). The mirrored checkerboard the FFT left out has no even part: nothing is lost.
Image integrate_mirrored(const Image& normals) {
    const int w = normals.width(), h = normals.height();
    const std::size_t n = std::size_t(w) * std::size_t(h);
    fftw::RealBuffer buffer = fftw::alloc_real(n);
    double* f = buffer.get();
    // D^T g at (x, y): (g[x-1] - g[x+1]) / 2 per axis, g odd beyond the border (g[-1] = -g[0]).
    const auto slope = [&](int x, int y, bool along_x) {
        const int i = along_x ? x : y, last = along_x ? w - 1 : h - 1;
        const double sign = i < 0 || i > last ? -1.0 : 1.0;
        const int c = std::clamp(i, 0, last);
        const float* p = along_x ? normals.pixel(c, y) : normals.pixel(x, c);
        return sign * (along_x ? slope_x(p) : slope_y(p));
    };
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x)
                f[std::size_t(y) * std::size_t(w) + std::size_t(x)] =
                    0.5 * (slope(x - 1, y, true) - slope(x + 1, y, true)) +
                    0.5 * (slope(x, y - 1, false) - slope(x, y + 1, false));
    });
    // Eigenvalues sin^2(pi u / w) + sin^2(pi v / h); only (0, 0) is zero (sin^2(pi / 16384) is
    // 3.7e-8), and the solver leaves that term out.
    std::vector<double> sin2_u(static_cast<std::size_t>(w)), sin2_v(static_cast<std::size_t>(h));
    for (int u = 0; u < w; ++u) {
        const double su = std::sin(kPi * u / w);
        sin2_u[std::size_t(u)] = su * su;
    }
    for (int v = 0; v < h; ++v) {
        const double sv = std::sin(kPi * v / h);
        sin2_v[std::size_t(v)] = sv * sv;
    }
    fftw::solve_in_cosine_basis(f, w, h, [&](int u, int v) { return sin2_u[std::size_t(u)] + sin2_v[std::size_t(v)]; });
    Image height(w, h, 1);
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) mean += f[i];
    mean /= double(n);
    const double normalisation = 1.0 / (4.0 * double(n));  // REDFT10 then REDFT01
    for (std::size_t i = 0; i < n; ++i) height.data()[i] = float((f[i] - mean) * normalisation);
    return height;
}

}  // namespace

Image integrate_normal_map(const Image& normals, bool periodic, const std::string& what) {
    TDF_CHECK(normals.channels() >= 3);
    const int w = normals.width(), h = normals.height();
    if (w < 3 || h < 3) throw_error("{}: a {}x{} map is too small to integrate (at least 3x3)", what, w, h);
    if (!normals.all_finite()) throw_error("{}: the normal map contains NaN or infinity", what);
    return periodic ? integrate_periodic(normals) : integrate_mirrored(normals);
}

double height_normal_consistency(const Image& height_mm, float mm_per_texel, const Image& normals, bool periodic,
                                 const Image& mask) {
    TDF_CHECK(normals.channels() >= 3 && mm_per_texel > 0);
    TDF_CHECK(height_mm.width() == normals.width() && height_mm.height() == normals.height());
    TDF_CHECK(mask.empty() || mask.pixel_count() == normals.pixel_count());
    const Image recomputed = normals_from_height(height_mm, 1.0f / mm_per_texel, periodic);
    double sum = 0, count = 0;
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        if (!mask.empty() && !(mask.data()[p * std::size_t(mask.channels())] > 0)) continue;
        const float* a = normals.data() + p * std::size_t(normals.channels());
        const float* b = recomputed.data() + 3 * p;
        const double length = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
        if (!(length > 0)) continue;
        sum += (double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]) / length;
        count += 1;
    }
    return count > 0 ? sum / count : 0.0;
}

ExportedHeight export_height(const Image& normals, const ExportScale& scale, const std::string& source,
                             const Image& mask) {
    TDF_CHECK(scale.mm_per_texel > 0);
    ExportedHeight out;
    out.map.height = integrate_normal_map(normals, scale.periodic, source);
    for (float& v : out.map.height.values()) v *= scale.mm_per_texel;
    out.map.mm_per_pixel = scale.mm_per_texel;
    out.map.tileable = scale.periodic;
    out.map.source = source;
    const auto [lo, hi] = std::minmax_element(out.map.height.values().begin(), out.map.height.values().end());
    out.min_mm = *lo, out.max_mm = *hi;
    out.assumed_pixel_size = scale.assumed;
    out.mean_cosine = height_normal_consistency(out.map.height, scale.mm_per_texel, normals, scale.periodic, mask);
    return out;
}

void write_exported_height(const std::string& base, const ExportedHeight& height) {
    // Three independent files, each encoded on one thread: side by side.
    std::vector<std::function<void()>> writes = {
        [&] { write_height_map(base + "_height.exr", height.map); },
        [&] { write_height_preview_png(base + "_height.png", height.map); }};
    if (!height.occlusion.empty())
        writes.push_back([&] { write_png(base + "_ao.png", height.occlusion, 8, Quantize::Round); });
    parallel_tasks(writes);
}

Json exported_height_json(const ExportedHeight& height, const ExportScale& scale, const std::string& png_name,
                          const std::string& exr_name) {
    Json j = {{"png", png_name},
              {"exr", exr_name},
              {"mm_per_texel", scale.mm_per_texel},
              {"mm_per_texel_assumed", scale.assumed},
              {"min_mm", height.min_mm},
              {"max_mm", height.max_mm},
              {"mm_per_step", height.mm_per_step()},
              {"normal_consistency_cosine", height.mean_cosine}};
    if (!height.occlusion.empty()) {
        double mean = 0;
        for (float v : height.occlusion.values()) mean += v;
        j["ambient_occlusion"] = {{"png", png_name.substr(0, png_name.size() - std::string("_height.png").size()) + "_ao.png"},
                                  {"radius_texels", kAoRadiusTexels},
                                  {"directions", kAoDirections},
                                  {"mean_visibility", mean / double(height.occlusion.pixel_count())}};
    }
    if (!height.metric.empty()) {
        j["texel_size"] = height.metric;  // "map": one size; "surface": each texel its own on the mesh
        j["texture_space_cosine"] = height.texture_space_cosine;
        j["surface_cosine"] = height.surface_cosine;
        j["seam_links"] = height.seam_links;
        j["seam_levelling"] = height.seam_levelling;
    }
    if (scale.capture_mm_per_pixel > 0)
        j["capture"] = {{"mm_per_pixel", scale.capture_mm_per_pixel},
                        {"width", scale.capture_width},
                        {"height", scale.capture_height}};
    if (scale.mm_per_unit > 0) {
        j["mm_per_unit"] = scale.mm_per_unit;
        // Blender's Displace modifier: offset = strength * (texture - midlevel), in mesh units,
        // texture = the PNG's value in [0, 1]: strength = range / mm_per_unit, midlevel = the
        // value of height 0 (the mean surface).
        const double range = double(height.max_mm - height.min_mm);
        j["displacement_strength"] = range / double(scale.mm_per_unit);
        j["displacement_midlevel"] = range > 0 ? double(-height.min_mm) / range : 0.5;
    }
    return j;
}

}  // namespace tdf
