#pragma once
/// Image operations: bilinear sampling, resizing (bilinear, area, Lanczos), 2x box reductions
/// and their adjoints, and separable (Gaussian) filters. The one implementation of each, shared
/// by the renderer, the texture pyramid, bakes, guidance, tactile processing and the losses.
///
/// Pixel-centre convention everywhere: pixel i covers [i, i + 1) and has its centre at i + 0.5.
/// "Texel coordinates" put the centres at integers (x = 0 is the centre of column 0), so a
/// UV (OBJ convention, v up) maps to x = u W - 0.5, y = (1 - v) H - 0.5 (uv_to_texel).
/// Parallel loops write disjoint outputs or reduce in a fixed order, so every result is the
/// same on any thread count.
#include <tdf/core/image.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace tdf {

/// What a lookup outside [0, n) reads.
enum class Addressing {
    Clamp,   ///< the edge pixel (coordinates clamped to the edge centres before interpolating)
    Wrap,    ///< periodic: ... n-1 | 0 1 .. n-1 | 0 ... (tiling textures, nvdiffrast's wrap)
    Mirror,  ///< reflect-101 without repeating the edge: ... 2 1 | 0 1 .. n-1 | n-2 ... (OpenCV's default)
    Border,  ///< zero
};

/// Index `i` of an axis of `n` pixels under `mode`; -1 for Border outside [0, n).
inline int address(int i, int n, Addressing mode) {
    if (i >= 0 && i < n) return i;
    switch (mode) {
        case Addressing::Clamp: return i < 0 ? 0 : n - 1;
        case Addressing::Wrap: {
            const int r = i % n;
            return r < 0 ? r + n : r;
        }
        case Addressing::Mirror: {
            if (n == 1) return 0;
            const int period = 2 * (n - 1);
            const int r = std::abs(i) % period;
            return r >= n ? period - r : r;
        }
        case Addressing::Border: break;
    }
    return -1;
}

/// A rectangle of interleaved floats somebody else owns: `width` x `height` pixels of `channels`
/// floats, rows `row_stride` floats apart (>= width * channels). Lets the filters below run on
/// buffers that are not Images (image batches, rows of a larger image) without copies.
struct ImageView {
    float* data = nullptr;
    int width = 0, height = 0, channels = 0;
    std::size_t row_stride = 0;

    ImageView() = default;
    ImageView(float* values, int w, int h, int c, std::size_t stride = 0)
        : data(values), width(w), height(h), channels(c),
          row_stride(stride ? stride : std::size_t(w) * std::size_t(c)) {}
    ImageView(Image& image)  // NOLINT(google-explicit-constructor): an Image is a view of itself
        : ImageView(image.data(), image.width(), image.height(), image.channels()) {}
    float* row(int y) const { return data + std::size_t(y) * row_stride; }
};

/// Read-only ImageView.
struct ConstImageView {
    const float* data = nullptr;
    int width = 0, height = 0, channels = 0;
    std::size_t row_stride = 0;

    ConstImageView() = default;
    ConstImageView(const float* values, int w, int h, int c, std::size_t stride = 0)
        : data(values), width(w), height(h), channels(c),
          row_stride(stride ? stride : std::size_t(w) * std::size_t(c)) {}
    ConstImageView(const Image& image)  // NOLINT(google-explicit-constructor)
        : ConstImageView(image.data(), image.width(), image.height(), image.channels()) {}
    ConstImageView(const ImageView& v)  // NOLINT(google-explicit-constructor)
        : ConstImageView(v.data, v.width, v.height, v.channels, v.row_stride) {}
    const float* row(int y) const { return data + std::size_t(y) * row_stride; }
    const float* pixel(int x, int y) const { return row(y) + std::size_t(x) * std::size_t(channels); }
};

// ---------------------------------------------------------------------------------------------
// Bilinear sampling at arbitrary points

/// A point in texel coordinates (pixel centres at integers).
struct TexelPoint {
    float x, y;
};

/// Texel coordinates of the UV (u, v) (v up) on a width x height image: (u W - 0.5, (1 - v) H - 0.5).
inline TexelPoint uv_to_texel(float u, float v, int width, int height) {
    return {u * float(width) - 0.5f, (1.f - v) * float(height) - 0.5f};
}

/// The four pixels a bilinear lookup blends (columns x0, x1, rows y0, y1; -1 = zero under
/// Border) and the weights of x1 and y1. Lookups (sample_bilinear) and their adjoints (the
/// texture pyramid's taps) share it, so both address the same pixels with the same weights.
struct BilinearFootprint {
    int x0, x1, y0, y1;
    float ax, ay;
};

namespace image_ops_detail {
// floor(coordinate) as an index of an axis of n under Wrap; huge or non-finite coordinates take
// a slow path so the int conversion never overflows (non-finite: index 0, the weights are NaN).
inline int wrap_floor(float floored, int n) {
    const auto wrap = [](int i, int m) {
        if ((m & (m - 1)) == 0) return i & (m - 1);  // power of two (two's complement handles i < 0)
        const int r = i % m;
        return r < 0 ? r + m : r;
    };
    if (std::fabs(floored) < 1e9f) return wrap(int(floored), n);
    if (!std::isfinite(floored)) return 0;
    return wrap(int(std::fmod(floored, float(n))), n);
}

// One axis of a footprint: Clamp clamps the coordinate to the edge centres, so the edge pixel
// comes back exactly (weight 0 on the second tap); non-finite coordinates read pixel 0.
inline void clamp_axis(float x, int n, int& i0, int& i1, float& a) {
    x = std::isfinite(x) ? std::clamp(x, 0.0f, float(n - 1)) : 0.0f;
    i0 = std::min(int(x), n - 1);
    i1 = std::min(i0 + 1, n - 1);
    a = x - float(i0);
}

inline void border_axis(float x, int n, int& i0, int& i1, float& a) {
    if (!(std::fabs(x) < 1e9f)) {  // far outside, or not finite: nothing to read
        i0 = i1 = -1;
        a = 0.0f;
        return;
    }
    const float f = std::floor(x);
    a = x - f;
    i0 = int(f);
    i1 = i0 + 1;
    if (i0 < 0 || i0 >= n) i0 = -1;
    if (i1 < 0 || i1 >= n) i1 = -1;
}
}  // namespace image_ops_detail

/// The footprint at texel coordinates (x, y) of a width x height image under `mode` (Mirror
/// is not offered for point lookups: nothing samples that way).
inline BilinearFootprint bilinear_footprint(float x, float y, int width, int height, Addressing mode) {
    BilinearFootprint f;
    if (mode == Addressing::Wrap) {
        const float fx0 = std::floor(x), fy0 = std::floor(y);
        f.ax = x - fx0, f.ay = y - fy0;
        f.x0 = image_ops_detail::wrap_floor(fx0, width), f.y0 = image_ops_detail::wrap_floor(fy0, height);
        f.x1 = f.x0 + 1 == width ? 0 : f.x0 + 1, f.y1 = f.y0 + 1 == height ? 0 : f.y0 + 1;
    } else if (mode == Addressing::Border) {
        image_ops_detail::border_axis(x, width, f.x0, f.x1, f.ax);
        image_ops_detail::border_axis(y, height, f.y0, f.y1, f.ay);
    } else {
        image_ops_detail::clamp_axis(x, width, f.x0, f.x1, f.ax);
        image_ops_detail::clamp_axis(y, height, f.y0, f.y1, f.ay);
    }
    return f;
}

namespace image_ops_detail {
// `channels` zeros: what Border reads outside the image (up to 64 channels).
const float* zero_pixel(int channels);
}  // namespace image_ops_detail

/// Blends the footprint's four pixels of `image` into `out` (image.channels floats):
/// w00 p00 + w10 p10 + w01 p01 + w11 p11 with w10 = ax (1 - ay) and so on. `Channels` > 0 fixes
/// the channel count at compile time (it must equal image.channels) for callers in hot loops
/// that dispatch on it, like the texture pyramid.
template <int Channels = 0>
inline void blend_footprint(ConstImageView image, const BilinearFootprint& f, float* out) {
    const int c = Channels > 0 ? Channels : image.channels;
    const float *p00, *p10, *p01, *p11;
    if ((f.x0 | f.x1 | f.y0 | f.y1) >= 0) {
        p00 = image.pixel(f.x0, f.y0), p10 = image.pixel(f.x1, f.y0);
        p01 = image.pixel(f.x0, f.y1), p11 = image.pixel(f.x1, f.y1);
    } else {  // Border outside the image
        const float* zero = image_ops_detail::zero_pixel(c);
        const auto at = [&](int x, int y) { return x < 0 || y < 0 ? zero : image.pixel(x, y); };
        p00 = at(f.x0, f.y0), p10 = at(f.x1, f.y0), p01 = at(f.x0, f.y1), p11 = at(f.x1, f.y1);
    }
    const float ax = f.ax, ay = f.ay;
    const float w00 = (1 - ax) * (1 - ay), w10 = ax * (1 - ay), w01 = (1 - ax) * ay, w11 = ax * ay;
    for (int k = 0; k < c; ++k) out[k] = w00 * p00[k] + w10 * p10[k] + w01 * p01[k] + w11 * p11[k];
}

/// Bilinear lookup at texel coordinates (x, y) (centres at integers) under `mode` (Clamp, Wrap
/// or Border); writes image.channels floats to `out`.
inline void sample_bilinear_texel(ConstImageView image, float x, float y, Addressing mode, float* out) {
    blend_footprint(image, bilinear_footprint(x, y, image.width, image.height, mode), out);
}

/// Bilinear lookup at the UV (u, v) (v up, texel centres at ((j + 0.5) / W, 1 - (i + 0.5) / H)).
inline void sample_bilinear_uv(ConstImageView image, float u, float v, Addressing mode, float* out) {
    const TexelPoint t = uv_to_texel(u, v, image.width, image.height);
    sample_bilinear_texel(image, t.x, t.y, mode, out);
}

// ---------------------------------------------------------------------------------------------
// Resizing

/// One axis of a bilinear resize from `source` to `size` pixels: output o reads source pixels
/// i0[o] (weight 1 - w1[o]) and i1[o] (weight w1[o]) at (o + 0.5) source / size - 0.5, the
/// position clamped to the edge centres (Clamp addressing; PyTorch's
/// interpolate(mode="bilinear", align_corners=False) without antialias, spec 3.8).
struct BilinearResizeTaps {
    std::vector<int> i0, i1;
    std::vector<float> w1;
};
BilinearResizeTaps bilinear_resize_taps(int source, int size);

/// `image` resized to width x height (any sizes, down or up) by bilinear interpolation with the
/// taps above; every channel. The same size returns a copy. Empty sizes throw tdf::Error.
Image resize_bilinear(const Image& image, int width, int height);

/// The exact adjoint (transpose) of resize_bilinear for a source_width x source_height source:
/// <resize_bilinear(x), y> == <x, resize_bilinear_adjoint(y)>. `grad` has the resized size;
/// the result has the source size. The summation order does not depend on the thread count.
Image resize_bilinear_adjoint(const Image& grad, int source_width, int source_height);

/// `image` resized to width x height by area averaging (box filter): each output pixel is the
/// average of the source area it covers, partial pixels weighted by coverage. For halving an
/// even size that is the plain 2x2 mean.
Image resize_area(const Image& image, int width, int height);
/// resize_area() into `out`, whose size (and image's channel count) says the target; reuses
/// out's storage.
void resize_area_into(const Image& image, Image& out);
/// The adjoint of resize_area(): adds to `fine` (the source's size) the gradient that `coarse`
/// (the gradient of resize_area(fine)) sends back through the area weights.
void resize_area_adjoint(const Image& coarse, Image& fine);

/// One level of a mip pyramid from the previous one: max(1, floor(size / 2)) per axis, each
/// texel the area average of the texels it covers (resize_area): the 2x2 box filter of spec 3.7
/// for even sizes and a footprint of 2 + 1 / size_out texels for odd sizes.
Image downsample_box(const Image& image);
/// downsample_box() into `out` (sized max(1, w / 2) x max(1, h / 2), image's channels).
void downsample_box_into(const Image& image, Image& out);
/// The adjoint of downsample_box(): adds to `fine` what `coarse` (the gradient of
/// downsample_box(fine)) sends back.
void downsample_box_adjoint(const Image& coarse, Image& fine);

/// Halves the size rounding UP ((n + 1) / 2 per axis) by averaging 2x2 blocks; the last block of
/// an odd size averages the pixels it has. The guidance pyramids' reduction (it keeps a pixel for
/// every odd edge); the mip pyramid (downsample_box) rounds down as nvdiffrast does.
Image downsample_half(const Image& image);

/// Lanczos-4 resampling (8 taps, OpenCV INTER_LANCZOS4 when enlarging: source position
/// (i + 0.5) * scale - 0.5, borders replicated, weights normalised to sum 1). When shrinking, the
/// kernel is widened by the shrink factor so that it also low-passes (OpenCV does not). Values
/// are not clamped: like the reference, results can overshoot the input range slightly.
Image resize_lanczos(const Image& image, int width, int height);

// ---------------------------------------------------------------------------------------------
// Separable filters

/// Gaussian weights exp(-i^2 / (2 sigma^2)) for i = -radius .. radius, divided by their sum when
/// `normalise`.
template <class T>
std::vector<T> gaussian_kernel(T sigma, int radius, bool normalise = true) {
    std::vector<T> kernel(std::size_t(2 * radius + 1));
    T total = 0;
    for (int i = -radius; i <= radius; ++i)
        total += kernel[std::size_t(i + radius)] = std::exp(T(-0.5) * T(i * i) / (sigma * sigma));
    if (normalise)
        for (T& k : kernel) k /= total;
    return kernel;
}

/// out = K_y * (K_x * in): the odd-length `kernel` along x then along y, every channel, pixels
/// outside read per `mode`. Each output is accumulated from 0 in kernel order (float kernels in
/// float, double kernels in double; the pass between is stored as float). `out` has in's shape
/// and may be the same buffer as `in`: then no full-size buffer is made (same bits).
void convolve_separable(ConstImageView in, ImageView out, const std::vector<float>& kernel, Addressing mode);
void convolve_separable(ConstImageView in, ImageView out, const std::vector<double>& kernel, Addressing mode);

/// Mask-weighted separable Gaussian blur: out = G*(m x) / G*(m) per channel, so background
/// (mask 0) does not bleed into the foreground. `mask` is 1 channel of the image's size, or empty
/// for weight 1 everywhere. Pixels whose blurred weight is 0 keep their value. `sigma` in pixels;
/// the kernel has radius ceil(3 sigma) and Clamp addressing. sigma <= 0 returns a copy.
Image gaussian_blur_masked(const Image& image, const Image& mask, float sigma);

/// resize_bilinear(gaussian_blur_masked(image, mask, sigma), width, height), the same numbers,
/// but the blur is evaluated only at the pixels the bilinear lookup reads (horizontal taps at
/// the needed columns of the needed rows, vertical taps at the needed pixels). Shrinking a
/// 512^2 image 19x this costs about a twentieth of blurring it whole, which is what a
/// prefiltered coarse copy needs: anti-aliased downsampling without full-size temporaries.
Image gaussian_blur_resized(const Image& image, const Image& mask, float sigma, int width, int height);

}  // namespace tdf
