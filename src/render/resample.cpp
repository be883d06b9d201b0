#include <tdf/render/resample.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <vector>

namespace tdf {

namespace {

// One axis of the PyTorch linear kernel: destination d reads source i0 with weight w0 and
// i1 with weight 1 - w0 (aten/src/ATen/native/UpSample.h, area_pixel_compute_source_index).
struct LinearTaps {
    std::vector<int> i0, i1;
    std::vector<float> w0;
};

LinearTaps linear_taps(int src, int dst) {
    LinearTaps taps;
    taps.i0.resize(std::size_t(dst));
    taps.i1.resize(std::size_t(dst));
    taps.w0.resize(std::size_t(dst));
    const float scale = float(src) / float(dst);
    for (int d = 0; d < dst; ++d) {
        const float s = std::max(0.f, scale * (float(d) + 0.5f) - 0.5f);
        const int i0 = std::min(int(s), src - 1);
        const int i1 = std::min(i0 + 1, src - 1);
        const float lambda = s - float(i0);
        taps.i0[std::size_t(d)] = i0;
        taps.i1[std::size_t(d)] = i1;
        taps.w0[std::size_t(d)] = 1.f - lambda;
    }
    return taps;
}

void check_size(int width, int height, const char* what) {
    if (width <= 0 || height <= 0) throw_error("{} size {}x{} is empty", what, width, height);
}

}  // namespace

Image downsample_bilinear(const Image& src, int width, int height) {
    check_size(width, height, "resize target");
    check_size(src.width(), src.height(), "resize source");
    if (src.width() == width && src.height() == height) return src;
    const LinearTaps tx = linear_taps(src.width(), width), ty = linear_taps(src.height(), height);
    const int c = src.channels();
    Image dst(width, height, c);
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y) {
            const float wy0 = ty.w0[y], wy1 = 1.f - wy0;
            for (int x = 0; x < width; ++x) {
                const float wx0 = tx.w0[std::size_t(x)], wx1 = 1.f - wx0;
                const float* a = src.pixel(tx.i0[std::size_t(x)], ty.i0[y]);
                const float* b = src.pixel(tx.i1[std::size_t(x)], ty.i0[y]);
                const float* p = src.pixel(tx.i0[std::size_t(x)], ty.i1[y]);
                const float* q = src.pixel(tx.i1[std::size_t(x)], ty.i1[y]);
                float* out = dst.pixel(x, int(y));
                for (int k = 0; k < c; ++k)
                    out[k] = wy0 * (wx0 * a[k] + wx1 * b[k]) + wy1 * (wx0 * p[k] + wx1 * q[k]);
            }
        }
    });
    return dst;
}

Image downsample_bilinear_adjoint(const Image& grad_out, int src_width, int src_height) {
    check_size(src_width, src_height, "adjoint source");
    if (src_width == grad_out.width() && src_height == grad_out.height()) return grad_out;
    const int width = grad_out.width(), height = grad_out.height(), c = grad_out.channels();
    const LinearTaps tx = linear_taps(src_width, width), ty = linear_taps(src_height, height);
    // The separable transpose: along x each destination row scatters into its own row of
    // `rows` (disjoint, so rows run in parallel); along y the rows are accumulated in order.
    Image rows(src_width, height, c);
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y)
            for (int x = 0; x < width; ++x) {
                const float* g = grad_out.pixel(x, int(y));
                float* a = rows.pixel(tx.i0[std::size_t(x)], int(y));
                float* b = rows.pixel(tx.i1[std::size_t(x)], int(y));
                const float w0 = tx.w0[std::size_t(x)], w1 = 1.f - w0;
                for (int k = 0; k < c; ++k) {
                    a[k] += w0 * g[k];
                    b[k] += w1 * g[k];
                }
            }
    });
    Image result(src_width, src_height, c);
    const std::size_t row_floats = std::size_t(src_width) * std::size_t(c);
    // Sequential over y so the summation order never depends on the thread count.
    for (int y = 0; y < height; ++y) {
        const float w0 = ty.w0[std::size_t(y)], w1 = 1.f - w0;
        const float* g = rows.pixel(0, y);
        float* a = result.pixel(0, ty.i0[std::size_t(y)]);
        float* b = result.pixel(0, ty.i1[std::size_t(y)]);
        for (std::size_t k = 0; k < row_floats; ++k) {
            a[k] += w0 * g[k];
            b[k] += w1 * g[k];
        }
    }
    return result;
}

}  // namespace tdf
