#include <tdf/tactile/high_pass.h>

#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>
#include "fftw_plan_impl.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace tdf {

namespace {

void subtract_minimum(Image& image) {
    const float lowest = *std::min_element(image.values().begin(), image.values().end());
    for (float& v : image.values()) v -= lowest;
}

// Signed frequency of FFT bin `b` of an axis of length n, as numpy's fftshift orders them:
// -n/2 .. n/2 - 1 for even n (the Nyquist bin counts as negative), -(n-1)/2 .. (n-1)/2 for odd.
int signed_frequency(int b, int n) { return b < (n + 1) / 2 ? b : b - n; }

// True when signed frequency `k` lies in the reference's block [-t, t) (spec 6.2 step 2).
bool in_block(int k, int t) { return k >= -t && k < t; }

}  // namespace

Image high_pass_fft_block(const Image& height, int threshold) {
    TDF_CHECK_EQ(height.channels(), 1);
    const int w = height.width(), h = height.height();
    if (threshold < 1) throw_error("high-pass threshold must be at least 1, got {}", threshold);
    if (w <= 2 * threshold || h <= 2 * threshold)
        throw_error("high-pass: a {}x{} image is too small for threshold {}", w, h, threshold);
    const int half = w / 2 + 1;
    fftw::RealBuffer real = fftw::alloc_real(std::size_t(w) * std::size_t(h));
    fftw::ComplexBuffer spectrum = fftw::alloc_complex(std::size_t(half) * std::size_t(h));
    const fftw::Plan forward = fftw::plan_r2c(w, h, real.get(), spectrum.get());
    const fftw::Plan inverse = fftw::plan_c2r(w, h, spectrum.get(), real.get());
    for (std::size_t i = 0; i < height.pixel_count(); ++i) real[i] = height.data()[i];
    fftw_execute(forward.get());
    // The reference keeps Re(ifft(X * M)) with a block mask M that is not symmetric; that equals
    // ifft(X * (M(k) + M(-k)) / 2), which is what we apply on the half spectrum.
    for (int ky = 0; ky < h; ++ky) {
        const int sy = signed_frequency(ky, h), my = signed_frequency((h - ky) % h, h);
        for (int kx = 0; kx < half; ++kx) {
            const int sx = signed_frequency(kx, w), mx = signed_frequency((w - kx) % w, w);
            const double blocked = 0.5 * (double(in_block(sy, threshold) && in_block(sx, threshold)) +
                                          double(in_block(my, threshold) && in_block(mx, threshold)));
            const double keep = (1.0 - blocked) / (double(w) * double(h));  // FFTW does not normalise
            fftw_complex& c = spectrum[std::size_t(ky) * std::size_t(half) + std::size_t(kx)];
            c[0] *= keep;
            c[1] *= keep;
        }
    }
    fftw_execute(inverse.get());
    Image out(w, h, 1);
    for (std::size_t i = 0; i < out.pixel_count(); ++i) out.data()[i] = float(real[i]);
    subtract_minimum(out);
    return out;
}

Image high_pass_gaussian(const Image& height, float cutoff_mm, float mm_per_pixel) {
    TDF_CHECK_EQ(height.channels(), 1);
    if (!(cutoff_mm > 0) || !(mm_per_pixel > 0))
        throw_error("Gaussian high-pass needs a positive cut-off and pixel size, got {} mm and {} mm/px",
                    cutoff_mm,
                    mm_per_pixel);
    const float sigma = 0.18739f * cutoff_mm / mm_per_pixel;  // sqrt(ln 2 / pi) / sqrt(2 pi)
    const int radius = std::max(1, int(std::ceil(3.0f * sigma)));
    Image blurred(height.width(), height.height(), 1);
    convolve_separable(height, blurred, gaussian_kernel<float>(sigma, radius), Addressing::Mirror);
    for (std::size_t i = 0; i < blurred.values().size(); ++i) blurred.values()[i] = height.values()[i] - blurred.values()[i];
    subtract_minimum(blurred);
    return blurred;
}

Image bilateral_filter(const Image& image, int diameter, float sigma_color, float sigma_space) {
    TDF_CHECK_EQ(image.channels(), 1);
    if (diameter < 1 || !(sigma_color > 0) || !(sigma_space > 0))
        throw_error("bilateral filter: diameter {} and sigmas {}, {} must be positive",
                    diameter,
                    sigma_color,
                    sigma_space);
    const int radius = diameter / 2;
    struct Tap {
        int dx, dy;
        float weight;
    };
    std::vector<Tap> taps;
    for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
            const float r2 = float(dx * dx + dy * dy);
            if (std::sqrt(r2) > float(radius)) continue;  // OpenCV's disc
            taps.push_back({dx, dy, std::exp(-r2 / (2.0f * sigma_space * sigma_space))});
        }
    const float color_scale = -1.0f / (2.0f * sigma_color * sigma_color);
    const int w = image.width(), h = image.height();
    Image out(w, h, 1);
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                const float centre = image.at(x, y, 0);
                float sum = 0, weights = 0;
                for (const Tap& t : taps) {
                    const float v = image.at(address(x + t.dx, w, Addressing::Mirror), address(y + t.dy, h, Addressing::Mirror), 0);
                    const float weight = t.weight * std::exp((v - centre) * (v - centre) * color_scale);
                    sum += weight * v;
                    weights += weight;
                }
                out.at(x, y, 0) = sum / weights;
            }
    });
    return out;
}

}  // namespace tdf
