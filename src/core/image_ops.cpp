#include <tdf/core/image_ops.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

namespace tdf {

namespace image_ops_detail {
const float* zero_pixel(int channels) {
    static const std::array<float, 64> zeros{};
    TDF_CHECK_LE(channels, int(zeros.size()));
    return zeros.data();
}
}  // namespace image_ops_detail

namespace {

void check_size(int width, int height, const char* what) {
    if (width <= 0 || height <= 0) throw_error("{} size {}x{} is empty", what, width, height);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Bilinear resize

BilinearResizeTaps bilinear_resize_taps(int source, int size) {
    BilinearResizeTaps taps;
    taps.i0.resize(std::size_t(size));
    taps.i1.resize(std::size_t(size));
    taps.w1.resize(std::size_t(size));
    const float scale = float(source) / float(size);
    for (int o = 0; o < size; ++o) {
        const float s = std::clamp((float(o) + 0.5f) * scale - 0.5f, 0.0f, float(source - 1));
        const int i0 = std::min(int(s), source - 1);
        taps.i0[std::size_t(o)] = i0;
        taps.i1[std::size_t(o)] = std::min(i0 + 1, source - 1);
        taps.w1[std::size_t(o)] = s - float(i0);
    }
    return taps;
}

Image resize_bilinear(const Image& image, int width, int height) {
    check_size(width, height, "resize target");
    check_size(image.width(), image.height(), "resize source");
    if (image.width() == width && image.height() == height) return image;
    const BilinearResizeTaps tx = bilinear_resize_taps(image.width(), width);
    const BilinearResizeTaps ty = bilinear_resize_taps(image.height(), height);
    const int c = image.channels();
    Image out(width, height, c);
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y) {
            const float wy = ty.w1[y];
            for (int x = 0; x < width; ++x) {
                const std::size_t xs = std::size_t(x);
                const float wx = tx.w1[xs];
                const float* a = image.pixel(tx.i0[xs], ty.i0[y]);
                const float* b = image.pixel(tx.i1[xs], ty.i0[y]);
                const float* p = image.pixel(tx.i0[xs], ty.i1[y]);
                const float* q = image.pixel(tx.i1[xs], ty.i1[y]);
                float* dst = out.pixel(x, int(y));
                for (int k = 0; k < c; ++k) {
                    const float top = a[k] * (1 - wx) + b[k] * wx;
                    const float bottom = p[k] * (1 - wx) + q[k] * wx;
                    dst[k] = top * (1 - wy) + bottom * wy;
                }
            }
        }
    });
    return out;
}

Image resize_bilinear_adjoint(const Image& grad, int source_width, int source_height) {
    check_size(source_width, source_height, "adjoint source");
    if (source_width == grad.width() && source_height == grad.height()) return grad;
    const int width = grad.width(), height = grad.height(), c = grad.channels();
    const BilinearResizeTaps tx = bilinear_resize_taps(source_width, width);
    const BilinearResizeTaps ty = bilinear_resize_taps(source_height, height);
    // The separable transpose: along x each destination row scatters into its own row of
    // `rows` (disjoint, so rows run in parallel); along y the rows are accumulated in order.
    Image rows(source_width, height, c);
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y)
            for (int x = 0; x < width; ++x) {
                const std::size_t xs = std::size_t(x);
                const float* g = grad.pixel(x, int(y));
                float* a = rows.pixel(tx.i0[xs], int(y));
                float* b = rows.pixel(tx.i1[xs], int(y));
                const float w1 = tx.w1[xs], w0 = 1 - w1;
                for (int k = 0; k < c; ++k) {
                    a[k] += w0 * g[k];
                    b[k] += w1 * g[k];
                }
            }
    });
    Image result(source_width, source_height, c);
    const std::size_t row_floats = std::size_t(source_width) * std::size_t(c);
    // Sequential over y so the summation order never depends on the thread count.
    for (int y = 0; y < height; ++y) {
        const std::size_t ys = std::size_t(y);
        const float w1 = ty.w1[ys], w0 = 1 - w1;
        const float* g = rows.pixel(0, y);
        float* a = result.pixel(0, ty.i0[ys]);
        float* b = result.pixel(0, ty.i1[ys]);
        for (std::size_t k = 0; k < row_floats; ++k) {
            a[k] += w0 * g[k];
            b[k] += w1 * g[k];
        }
    }
    return result;
}

// ---------------------------------------------------------------------------------------------
// Area resize and the 2x reductions

namespace {

// One axis of an area resize: output pixel d covers source interval [d s, (d+1) s),
// s = source / size, and reads the `count[d]` source pixels from `first[d]` it overlaps with
// weight overlap / s (`stride` weights per output pixel).
struct AreaTaps {
    std::vector<int> first, count;
    std::vector<float> weights;
    std::size_t stride = 0;
    const float* weight(std::size_t d) const { return weights.data() + d * stride; }
};

AreaTaps area_taps(int source, int size) {
    AreaTaps taps;
    const double scale = double(source) / double(size);
    taps.stride = std::size_t(std::ceil(scale)) + 1;
    taps.first.resize(std::size_t(size));
    taps.count.resize(std::size_t(size));
    taps.weights.assign(std::size_t(size) * taps.stride, 0.f);
    for (int d = 0; d < size; ++d) {
        const double lo = d * scale, hi = (d + 1) * scale;
        const int first = int(std::floor(lo));
        const int last = std::min(source - 1, int(std::ceil(hi)) - 1);
        taps.first[std::size_t(d)] = first;
        taps.count[std::size_t(d)] = last - first + 1;
        TDF_CHECK_LE(std::size_t(last - first + 1), taps.stride);
        for (int s = first; s <= last; ++s) {
            const double overlap = std::min(hi, double(s + 1)) - std::max(lo, double(s));
            taps.weights[std::size_t(d) * taps.stride + std::size_t(s - first)] = float(overlap / scale);
        }
    }
    return taps;
}

// The pixels of `fine` that coarse pixel (x, y) reads, with their weights: calls
// visit(fine_pixel_x, fine_pixel_y, weight) in a fixed order (rows, then columns).
template <class Visit>
inline void visit_area(const AreaTaps& tx, const AreaTaps& ty, std::size_t x, std::size_t y, Visit&& visit) {
    const float* wy = ty.weight(y);
    const float* wx = tx.weight(x);
    for (int j = 0; j < ty.count[y]; ++j)
        for (int i = 0; i < tx.count[x]; ++i) visit(tx.first[x] + i, ty.first[y] + j, wy[j] * wx[i]);
}

}  // namespace

void resize_area_into(const Image& image, Image& out) {
    check_size(out.width(), out.height(), "resize target");
    check_size(image.width(), image.height(), "resize source");
    TDF_CHECK_EQ(out.channels(), image.channels());
    const int w = out.width(), h = out.height(), c = image.channels();
    if (image.width() == 2 * w && image.height() == 2 * h) {
        // Exactly half the size (every mip level of an even map): each output value is its 2x2
        // block's mean, without the general taps. Summed from zero in visit_area's order with
        // its weight (0.5 x 0.5 = 0.25, exact), so the bits equal the general path's.
        const std::size_t row = std::size_t(w) * std::size_t(c);
        parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t y = y0; y < y1; ++y) {
                const float* top = image.pixel(0, int(2 * y));
                const float* bottom = image.pixel(0, int(2 * y + 1));
                float* dst = out.pixel(0, int(y));
                for (std::size_t i = 0; i < row; ++i) {
                    const std::size_t left = 2 * i - i % std::size_t(c), right = left + std::size_t(c);
                    float sum = 0.0f;
                    sum += 0.25f * top[left];
                    sum += 0.25f * top[right];
                    sum += 0.25f * bottom[left];
                    sum += 0.25f * bottom[right];
                    dst[i] = sum;
                }
            }
        });
        return;
    }
    const AreaTaps tx = area_taps(image.width(), w), ty = area_taps(image.height(), h);
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (std::size_t y = y0; y < y1; ++y)
            for (int x = 0; x < w; ++x) {
                float* dst = out.pixel(x, int(y));
                std::fill(dst, dst + c, 0.0f);
                visit_area(tx, ty, std::size_t(x), y, [&](int sx, int sy, float weight) {
                    const float* src = image.pixel(sx, sy);
                    for (int k = 0; k < c; ++k) dst[k] += weight * src[k];
                });
            }
    });
}

Image resize_area(const Image& image, int width, int height) {
    check_size(width, height, "resize target");
    Image out(width, height, image.channels());
    resize_area_into(image, out);
    return out;
}

void resize_area_adjoint(const Image& coarse, Image& fine) {
    const int w = coarse.width(), h = coarse.height(), c = coarse.channels();
    TDF_CHECK(c == fine.channels() && w > 0 && h > 0);
    if (fine.width() == 2 * w && fine.height() == 2 * h) {
        // Exactly half the size: each fine value gets one quarter of its block's gradient (the
        // general scatter's single term for it, same bits).
        const std::size_t row = std::size_t(w) * std::size_t(c);
        parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t y = y0; y < y1; ++y) {
                const float* g = coarse.pixel(0, int(y));
                float* top = fine.pixel(0, int(2 * y));
                float* bottom = fine.pixel(0, int(2 * y + 1));
                for (std::size_t i = 0; i < row; ++i) {
                    const std::size_t left = 2 * i - i % std::size_t(c), right = left + std::size_t(c);
                    const float quarter = 0.25f * g[i];
                    top[left] += quarter;
                    top[right] += quarter;
                    bottom[left] += quarter;
                    bottom[right] += quarter;
                }
            }
        });
        return;
    }
    const AreaTaps tx = area_taps(fine.width(), w), ty = area_taps(fine.height(), h);
    const auto scatter_row = [&](std::size_t y) {
        for (int x = 0; x < w; ++x) {
            const float* g = coarse.pixel(x, int(y));
            visit_area(tx, ty, std::size_t(x), y, [&](int fx, int fy, float weight) {
                float* dst = fine.pixel(fx, fy);
                for (int k = 0; k < c; ++k) dst[k] += weight * g[k];
            });
        }
    };
    // Coarse rows write disjoint fine rows when the height divides exactly; otherwise two coarse
    // rows share a fine row and the rows are scattered in order (one thread), so the sums never
    // depend on the thread count.
    if (fine.height() % h == 0) {
        parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t y = y0; y < y1; ++y) scatter_row(y);
        });
    } else {
        for (std::size_t y = 0; y < std::size_t(h); ++y) scatter_row(y);
    }
}

Image downsample_box(const Image& image) {
    return resize_area(image, std::max(1, image.width() / 2), std::max(1, image.height() / 2));
}

void downsample_box_into(const Image& image, Image& out) {
    TDF_CHECK(out.width() == std::max(1, image.width() / 2) && out.height() == std::max(1, image.height() / 2));
    resize_area_into(image, out);
}

void downsample_box_adjoint(const Image& coarse, Image& fine) {
    TDF_CHECK(coarse.width() == std::max(1, fine.width() / 2) && coarse.height() == std::max(1, fine.height() / 2));
    resize_area_adjoint(coarse, fine);
}

Image downsample_half(const Image& image) {
    const int w = (image.width() + 1) / 2, h = (image.height() + 1) / 2, c = image.channels();
    Image out(w, h, c);
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                int count = 0;
                float* dst = out.pixel(x, y);
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        const int sx = 2 * x + dx, sy = 2 * y + dy;
                        if (sx >= image.width() || sy >= image.height()) continue;
                        const float* src = image.pixel(sx, sy);
                        for (int ch = 0; ch < c; ++ch) dst[ch] += src[ch];
                        ++count;
                    }
                for (int ch = 0; ch < c; ++ch) dst[ch] /= float(count);
            }
    });
    return out;
}

// ---------------------------------------------------------------------------------------------
// Lanczos resize

namespace {

constexpr int kLanczosLobes = 4;

double lanczos(double x) {
    if (std::fabs(x) < 1e-12) return 1.0;
    if (std::fabs(x) >= kLanczosLobes) return 0.0;
    const double pi = 3.14159265358979323846;
    return kLanczosLobes * std::sin(pi * x) * std::sin(pi * x / kLanczosLobes) / (pi * pi * x * x);
}

// Sparse 1-D resampling matrix from `in` samples to `out` samples.
struct LanczosTaps {
    std::vector<int> index;     // clamped source indices, out * taps
    std::vector<float> weight;  // normalised weights, out * taps
    int taps = 0;
};

LanczosTaps lanczos_taps(int in, int out) {
    const double scale = double(in) / double(out);
    const double stretch = std::max(1.0, scale);  // widen the kernel when shrinking
    LanczosTaps t;
    t.taps = 2 * int(std::ceil(kLanczosLobes * stretch));
    t.index.resize(std::size_t(out) * std::size_t(t.taps));
    t.weight.resize(t.index.size());
    for (int o = 0; o < out; ++o) {
        const double centre = (o + 0.5) * scale - 0.5;
        const int start = int(std::floor(centre)) - t.taps / 2 + 1;
        double total = 0;
        for (int k = 0; k < t.taps; ++k) {
            const double w = lanczos((start + k - centre) / stretch);
            t.index[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] = address(start + k, in, Addressing::Clamp);
            t.weight[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] = float(w);
            total += w;
        }
        for (int k = 0; k < t.taps; ++k)
            t.weight[std::size_t(o) * std::size_t(t.taps) + std::size_t(k)] /= float(total);
    }
    return t;
}

// Resamples along x (`horizontal`) or y with precomputed taps; the other axis is unchanged.
Image lanczos_axis(const Image& image, const LanczosTaps& taps, int out_size, bool horizontal) {
    const int c = image.channels();
    const int width = horizontal ? out_size : image.width(), height = horizontal ? image.height() : out_size;
    Image out(width, height, c);
    parallel_for(std::size_t(height), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < width; ++x) {
                const std::size_t first = std::size_t(horizontal ? x : y) * std::size_t(taps.taps);
                for (int k = 0; k < c; ++k) {
                    float sum = 0;
                    for (int t = 0; t < taps.taps; ++t) {
                        const int source = taps.index[first + std::size_t(t)];
                        sum += taps.weight[first + std::size_t(t)] *
                               (horizontal ? image.at(source, y, k) : image.at(x, source, k));
                    }
                    out.at(x, y, k) = sum;
                }
            }
    });
    return out;
}

}  // namespace

Image resize_lanczos(const Image& image, int width, int height) {
    check_size(width, height, "resize target");
    check_size(image.width(), image.height(), "resize source");
    if (width == image.width() && height == image.height()) return image;
    const Image horizontal = lanczos_axis(image, lanczos_taps(image.width(), width), width, true);
    return lanczos_axis(horizontal, lanczos_taps(image.height(), height), height, false);
}

// ---------------------------------------------------------------------------------------------
// Separable filters

namespace {

// The filters' inner loop: out[i] = sum over k of kernel[k] * sources[k][i] for i < count, each
// output accumulated from 0 in kernel order (-radius .. radius), the same order for every pixel
// and every caller, so the filters below agree to the bit with one another and with a plain
// loop. Blocks of outputs stay in registers while the taps stream past. Built for AVX2 as well
// where the compiler can (mul and add stay separate instructions, so the bits do not change).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
__attribute__((target_clones("avx2", "default")))
#endif
void weighted_sum(const float* const* sources, const float* kernel, std::size_t taps, std::size_t count, float* out) {
    std::size_t start = 0;
#if defined(__GNUC__)
    // 32 outputs in four 8-float vectors (GCC/Clang vector extensions; two SSE registers each
    // without AVX). Written out because GCC's unroll-and-jam turns the plain loop scalar.
    typedef float Float8 __attribute__((vector_size(32)));
    for (; start + 32 <= count; start += 32) {
        Float8 sum[4] = {};
        for (std::size_t k = 0; k < taps; ++k) {
            const float w = kernel[k];
            const Float8 weight = {w, w, w, w, w, w, w, w};
            const float* src = sources[k] + start;
            for (int b = 0; b < 4; ++b) {
                Float8 v;
                std::memcpy(&v, src + 8 * b, sizeof(v));
                sum[b] += weight * v;
            }
        }
        std::memcpy(out + start, sum, sizeof(sum));
    }
#endif
    std::fill(out + start, out + count, 0.0f);
    for (std::size_t k = 0; k < taps; ++k)
        for (std::size_t i = start; i < count; ++i) out[i] += kernel[k] * sources[k][i];
}

// The same with a double kernel: sums in double (`accumulator` holds count doubles), rounded to
// float once at the end.
void weighted_sum(const float* const* sources, const double* kernel, std::size_t taps, std::size_t count,
                  double* accumulator, float* out) {
    std::fill(accumulator, accumulator + count, 0.0);
    for (std::size_t k = 0; k < taps; ++k)
        for (std::size_t i = 0; i < count; ++i) accumulator[i] += kernel[k] * double(sources[k][i]);
    for (std::size_t i = 0; i < count; ++i) out[i] = float(accumulator[i]);
}

// Fills the `radius` pixels (`stride` floats each) on both sides of a padded row whose `width`
// interior pixels start at pixel `radius`, as `mode` reads outside the row.
void pad_row(float* padded, int width, int radius, std::size_t stride, Addressing mode) {
    for (int i = -radius; i < 0; ++i) {
        for (const int x : {i, width - 1 - i}) {
            float* dst = padded + std::size_t(x + radius) * stride;
            const int source = address(x, width, mode);
            if (source < 0)
                std::fill_n(dst, stride, 0.0f);
            else
                std::copy_n(padded + std::size_t(source + radius) * stride, stride, dst);
        }
    }
}

// Full-size scratch buffers of the blurs, kept between calls: a fresh 4 MB buffer per blur costs
// more in page faults and zeroing than the blur's arithmetic. Thread-safe (a caller may run on
// any thread, and nested parallel loops may start another blur while one waits); contents never
// carry over (every value is written before it is read), so results do not depend on reuse.
class ScratchBuffer {
public:
    explicit ScratchBuffer(std::size_t size) {
        {
            std::lock_guard<std::mutex> lock(pool_mutex());
            if (!pool().empty()) {
                m_values = std::move(pool().back());
                pool().pop_back();
            }
        }
        if (m_values.size() < size) m_values.resize(size);
    }
    ~ScratchBuffer() {
        if (m_values.size() > kLargestKept) return;  // a rare huge image: given back to the system
        std::lock_guard<std::mutex> lock(pool_mutex());
        if (pool().size() < kKept) pool().push_back(std::move(m_values));
    }
    ScratchBuffer(const ScratchBuffer&) = delete;
    ScratchBuffer& operator=(const ScratchBuffer&) = delete;
    float* data() { return m_values.data(); }

private:
    // Enough for the images refined in parallel; at most 4 x 4 MB stay allocated: a 512^2 image
    // with 4 weighted channels, the guidance's blurs in the main job. A map-sized blur (the
    // measures' at 1024^2, 16 MB) gives its buffer back instead of holding it through the run.
    static constexpr std::size_t kKept = 4;
    static constexpr std::size_t kLargestKept = std::size_t(1) << 20;  // floats
    static std::vector<std::vector<float>>& pool() {
        static std::vector<std::vector<float>> buffers;
        return buffers;
    }
    static std::mutex& pool_mutex() {
        static std::mutex mutex;
        return mutex;
    }
    std::vector<float> m_values;
};

// One weighted_sum for either kernel type (float kernels sum in place, double ones through the
// accumulator).
struct RowSummer {
    std::vector<double> accumulator;
    void operator()(const float* const* sources, const std::vector<float>& kernel, std::size_t count, float* out) {
        weighted_sum(sources, kernel.data(), kernel.size(), count, out);
    }
    void operator()(const float* const* sources, const std::vector<double>& kernel, std::size_t count, float* out) {
        accumulator.resize(count);
        weighted_sum(sources, kernel.data(), kernel.size(), count, accumulator.data(), out);
    }
};

// The horizontal pass of the separable filters: for each row y, fill(y, interior) writes the
// row's `width` pixels (`stride` floats each) where the padded row keeps them, the margins are
// padded as `mode` reads outside, and the kernel's taps are summed into row y of `out`
// (width * stride floats per row).
template <class Kernel, class FillRow>
void horizontal_pass(int width, int height, std::size_t stride, const Kernel& kernel, Addressing mode,
                     const FillRow& fill, float* out) {
    const int radius = int(kernel.size() / 2);
    const std::size_t row = std::size_t(width) * stride;
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        std::vector<float> padded(std::size_t(width + 2 * radius) * stride);
        std::vector<const float*> sources(kernel.size());
        for (std::size_t k = 0; k < kernel.size(); ++k) sources[k] = padded.data() + k * stride;
        RowSummer sum;
        for (std::size_t y = y0; y < y1; ++y) {
            fill(int(y), padded.data() + std::size_t(radius) * stride);
            pad_row(padded.data(), width, radius, stride, mode);
            sum(sources.data(), kernel, row, out + y * row);
        }
    });
}

// The vertical pass: row y sums the rows of `rows` (`row` floats each, `height` of them) the
// kernel reads around it, whole rows at a time (so it vectorises), into target(y, scratch) (a row
// of the caller's, or `scratch`), then calls done(y, that row).
template <class Kernel, class Target, class Done>
void vertical_pass(const float* rows, std::size_t row, int height, const Kernel& kernel, Addressing mode,
                   const Target& target, const Done& done) {
    const int radius = int(kernel.size() / 2);
    const std::vector<float> zero_row(mode == Addressing::Border ? row : 0, 0.0f);
    parallel_for(std::size_t(height), 8, [&](std::size_t y0, std::size_t y1) {
        std::vector<const float*> sources(kernel.size());
        std::vector<float> scratch;
        RowSummer sum;
        for (int y = int(y0); y < int(y1); ++y) {
            for (int k = -radius; k <= radius; ++k) {
                const int source = address(y + k, height, mode);
                sources[std::size_t(k + radius)] = source < 0 ? zero_row.data() : rows + std::size_t(source) * row;
            }
            float* dst = target(y, scratch);
            sum(sources.data(), kernel, row, dst);
            done(y, dst);
        }
    });
}

// In place without a full-size buffer (a 4096^2 map's 4-channel gradient would need 268 MB):
// the horizontal pass writes each row back over itself (the row is copied into its padded
// scratch first), then the vertical pass runs over strips of columns, each strip copied out
// first. Every value is the same sum, in the same order, as in the two-pass buffer path.
template <class Kernel>
void convolve_separable_in_place(ImageView image, const Kernel& kernel, Addressing mode) {
    const int w = image.width, h = image.height, c = image.channels;
    const std::size_t row = std::size_t(w) * std::size_t(c);
    horizontal_pass(w, h, std::size_t(c), kernel, mode,
                    [&](int y, float* interior) { std::copy_n(image.row(y), row, interior); }, image.data);
    constexpr std::size_t kStripFloats = 256;
    const std::size_t strips = (row + kStripFloats - 1) / kStripFloats;
    parallel_for(strips, 1, [&](std::size_t s0, std::size_t s1) {
        std::vector<float> columns;
        for (std::size_t strip = s0; strip < s1; ++strip) {
            const std::size_t first = strip * kStripFloats, count = std::min(kStripFloats, row - first);
            columns.resize(count * std::size_t(h));
            for (int y = 0; y < h; ++y)
                std::copy_n(image.row(y) + first, count, columns.data() + std::size_t(y) * count);
            const auto output_row = [&](int y, std::vector<float>&) { return image.row(y) + first; };
            vertical_pass(columns.data(), count, h, kernel, mode, output_row, [](int, const float*) {});
        }
    });
}

template <class Kernel>
void convolve_separable_impl(ConstImageView in, ImageView out, const Kernel& kernel, Addressing mode) {
    TDF_CHECK(kernel.size() % 2 == 1);
    TDF_CHECK(in.width == out.width && in.height == out.height && in.channels == out.channels);
    const int w = in.width, h = in.height, c = in.channels;
    if (w == 0 || h == 0 || c == 0) return;
    const std::size_t row = std::size_t(w) * std::size_t(c);
    if (in.data == out.data && in.row_stride == row && out.row_stride == row) {
        convolve_separable_in_place(out, kernel, mode);
        return;
    }
    ScratchBuffer horizontal(row * std::size_t(h));
    horizontal_pass(w, h, std::size_t(c), kernel, mode,
                    [&](int y, float* interior) { std::copy_n(in.row(y), row, interior); }, horizontal.data());
    vertical_pass(horizontal.data(), row, h, kernel, mode,
                  [&](int y, std::vector<float>&) { return out.row(y); }, [](int, const float*) {});
}

// Row y of the mask-weighted image into `dst`: per pixel m * value per channel, then m (1 where
// `mask` is empty).
void weighted_row(const Image& image, const Image& mask, int y, float* dst) {
    const int w = image.width(), c = image.channels();
    const std::size_t stride = std::size_t(c + 1);
    const float* src_row = image.pixel(0, y);
    const float* mask_row = mask.empty() ? nullptr : mask.pixel(0, y);
    if (c == 3 && mask_row) {  // the common case, written out so it compiles to straight-line code
        for (int x = 0; x < w; ++x, dst += 4) {
            const float m = mask_row[x];
            const float* src = src_row + 3 * std::size_t(x);
            dst[0] = m * src[0], dst[1] = m * src[1], dst[2] = m * src[2], dst[3] = m;
        }
    } else {
        for (int x = 0; x < w; ++x, dst += stride) {
            const float m = mask_row ? mask_row[x] : 1.0f;
            const float* src = src_row + std::size_t(x) * std::size_t(c);
            for (int ch = 0; ch < c; ++ch) dst[ch] = m * src[ch];
            dst[c] = m;
        }
    }
}

// One output pixel of a horizontal pass: the taps of `kernel` over `src` (the padded row at the
// pixel's leftmost tap), accumulated as weighted_sum() does. Fixed channel counts let the
// compiler keep the sums in one register.
template <int Channels>
void taps(const float* src, const std::vector<float>& kernel, float* dst) {
    float sum[Channels] = {};
    for (std::size_t k = 0; k < kernel.size(); ++k)
        for (int ch = 0; ch < Channels; ++ch) sum[ch] += kernel[k] * src[k * Channels + std::size_t(ch)];
    std::copy_n(sum, Channels, dst);
}

void taps_any(const float* src, const std::vector<float>& kernel, int channels, float* dst) {
    std::fill(dst, dst + channels, 0.0f);
    for (std::size_t k = 0; k < kernel.size(); ++k)
        for (int ch = 0; ch < channels; ++ch)
            dst[ch] += kernel[k] * src[k * std::size_t(channels) + std::size_t(ch)];
}

// The masked blurs' kernel: unnormalised (the division by the blurred mask normalises).
std::vector<float> masked_blur_kernel(float sigma) {
    return gaussian_kernel<float>(sigma, int(std::ceil(3.0f * sigma)), false);
}

}  // namespace

void convolve_separable(ConstImageView in, ImageView out, const std::vector<float>& kernel, Addressing mode) {
    convolve_separable_impl(in, out, kernel, mode);
}

void convolve_separable(ConstImageView in, ImageView out, const std::vector<double>& kernel, Addressing mode) {
    convolve_separable_impl(in, out, kernel, mode);
}

Image gaussian_blur_masked(const Image& image, const Image& mask, float sigma) {
    if (sigma <= 0.0f) return image;
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(mask.empty() || (mask.width() == w && mask.height() == h && mask.channels() == 1));
    const std::vector<float> kernel = masked_blur_kernel(sigma);
    const int stride = c + 1;  // weighted channels, then the weight
    const std::size_t row = std::size_t(w) * std::size_t(stride);
    // Horizontal pass over the weighted image, built row by row (no full-size weighted copy).
    ScratchBuffer horizontal(row * std::size_t(h));
    horizontal_pass(w, h, std::size_t(stride), kernel, Addressing::Clamp,
                    [&](int y, float* interior) { weighted_row(image, mask, y, interior); }, horizontal.data());
    // Vertical pass, then the division.
    Image out = image;
    vertical_pass(
        horizontal.data(), row, h, kernel, Addressing::Clamp,
        [&](int, std::vector<float>& scratch) {
            scratch.resize(row);
            return scratch.data();
        },
        [&](int y, const float* sum) {
            for (int x = 0; x < w; ++x) {
                const float* s = sum + std::size_t(x) * std::size_t(stride);
                if (s[c] <= 0.0f) continue;
                float* dst = out.pixel(x, y);
                for (int ch = 0; ch < c; ++ch) dst[ch] = s[ch] / s[c];
            }
        });
    return out;
}

Image gaussian_blur_resized(const Image& image, const Image& mask, float sigma, int width, int height) {
    if (sigma <= 0.0f) return resize_bilinear(image, width, height);
    check_size(width, height, "resize target");
    check_size(image.width(), image.height(), "resize source");
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(mask.empty() || (mask.width() == w && mask.height() == h && mask.channels() == 1));
    const std::vector<float> kernel = masked_blur_kernel(sigma);
    const int radius = int(kernel.size() / 2);
    const int stride = c + 1;
    const BilinearResizeTaps tx = bilinear_resize_taps(w, width), ty = bilinear_resize_taps(h, height);

    // The blurred pixels the bilinear lookup reads: columns `cols` x rows `rows` (sorted, unique).
    const auto unique_sorted = [](const BilinearResizeTaps& taps) {
        std::vector<int> v = taps.i0;
        v.insert(v.end(), taps.i1.begin(), taps.i1.end());
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
        return v;
    };
    const std::vector<int> cols = unique_sorted(tx), rows = unique_sorted(ty);
    std::vector<int> col_slot(std::size_t(w), -1), row_slot(std::size_t(h), -1);
    for (std::size_t j = 0; j < cols.size(); ++j) col_slot[std::size_t(cols[j])] = int(j);
    for (std::size_t i = 0; i < rows.size(); ++i) row_slot[std::size_t(rows[i])] = int(i);
    // Rows the vertical taps of those rows read.
    std::vector<unsigned char> row_needed(std::size_t(h), 0);
    for (const int y : rows)
        for (int k = -radius; k <= radius; ++k) row_needed[std::size_t(address(y + k, h, Addressing::Clamp))] = 1;

    // Horizontal pass at the needed columns of the needed rows.
    const std::size_t hrow = cols.size() * std::size_t(stride);
    ScratchBuffer horizontal(hrow * std::size_t(h));
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        std::vector<float> padded(std::size_t(w + 2 * radius) * std::size_t(stride));
        for (std::size_t y = y0; y < y1; ++y) {
            if (!row_needed[y]) continue;
            weighted_row(image, mask, int(y), padded.data() + std::size_t(radius) * std::size_t(stride));
            pad_row(padded.data(), w, radius, std::size_t(stride), Addressing::Clamp);
            for (std::size_t j = 0; j < cols.size(); ++j) {
                float* dst = horizontal.data() + y * hrow + j * std::size_t(stride);
                const float* src = padded.data() + std::size_t(cols[j]) * std::size_t(stride);
                if (stride == 4)
                    taps<4>(src, kernel, dst);
                else if (stride == 2)
                    taps<2>(src, kernel, dst);
                else
                    taps_any(src, kernel, stride, dst);
            }
        }
    });
    // Vertical pass and division at the needed pixels: the blurred image there.
    const std::size_t brow = cols.size() * std::size_t(c);
    std::vector<float> blurred(brow * rows.size());
    parallel_for(rows.size(), 8, [&](std::size_t i0, std::size_t i1) {
        std::vector<float> sum(static_cast<std::size_t>(stride));
        for (std::size_t i = i0; i < i1; ++i)
            for (std::size_t j = 0; j < cols.size(); ++j) {
                std::fill(sum.begin(), sum.end(), 0.0f);
                for (int k = -radius; k <= radius; ++k) {
                    const float weight = kernel[std::size_t(k + radius)];
                    const float* src = horizontal.data() +
                                       std::size_t(address(rows[i] + k, h, Addressing::Clamp)) * hrow +
                                       j * std::size_t(stride);
                    for (int ch = 0; ch < stride; ++ch) sum[std::size_t(ch)] += weight * src[ch];
                }
                float* dst = blurred.data() + i * brow + j * std::size_t(c);
                const float* keep = image.pixel(cols[j], rows[i]);
                for (int ch = 0; ch < c; ++ch)
                    dst[ch] =
                        sum[std::size_t(c)] <= 0.0f ? keep[ch] : sum[std::size_t(ch)] / sum[std::size_t(c)];
            }
    });
    // Bilinear lookup, the arithmetic of resize_bilinear().
    Image out(width, height, c);
    for (int y = 0; y < height; ++y) {
        const std::size_t ys = std::size_t(y);
        const float* top_row = blurred.data() + std::size_t(row_slot[std::size_t(ty.i0[ys])]) * brow;
        const float* bottom_row = blurred.data() + std::size_t(row_slot[std::size_t(ty.i1[ys])]) * brow;
        const float wy = ty.w1[ys];
        for (int x = 0; x < width; ++x) {
            const std::size_t xs = std::size_t(x);
            const std::size_t a = std::size_t(col_slot[std::size_t(tx.i0[xs])]) * std::size_t(c);
            const std::size_t b = std::size_t(col_slot[std::size_t(tx.i1[xs])]) * std::size_t(c);
            const float wx = tx.w1[xs];
            float* dst = out.pixel(x, y);
            for (int ch = 0; ch < c; ++ch) {
                const float top = top_row[a + std::size_t(ch)] * (1 - wx) + top_row[b + std::size_t(ch)] * wx;
                const float bottom =
                    bottom_row[a + std::size_t(ch)] * (1 - wx) + bottom_row[b + std::size_t(ch)] * wx;
                dst[ch] = top * (1 - wy) + bottom * wy;
            }
        }
    }
    return out;
}

}  // namespace tdf
