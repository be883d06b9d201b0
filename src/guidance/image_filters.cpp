#include <tdf/guidance/image_filters.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

namespace tdf {

namespace {
std::vector<float> gaussian_kernel(float sigma) {
    const int radius = int(std::ceil(3.0f * sigma));
    std::vector<float> kernel(std::size_t(2 * radius + 1));
    for (int i = -radius; i <= radius; ++i)
        kernel[std::size_t(i + radius)] = std::exp(-0.5f * float(i * i) / (sigma * sigma));
    return kernel;
}

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

// One horizontal pass over one row: `padded` holds the row's values with `radius` clamped pixels
// added at each end ((width + 2 radius) * channels floats), `out` receives width * channels.
void convolve_row(const float* padded, const std::vector<float>& kernel, int count, int channels,
                  float* out) {
    std::vector<const float*> sources(kernel.size());
    for (std::size_t k = 0; k < kernel.size(); ++k) sources[k] = padded + k * std::size_t(channels);
    weighted_sum(sources.data(), kernel.data(), kernel.size(), std::size_t(count), out);
}

// Row y of the mask-weighted image with clamped padding: per pixel m * value per channel, then m
// (1 where `mask` is empty), for x in [-radius, width + radius).
void weighted_padded_row(const Image& image, const Image& mask, int y, int radius, float* padded) {
    const int w = image.width(), c = image.channels();
    const std::size_t stride = std::size_t(c + 1);
    const float* src_row = image.pixel(0, y);
    const float* mask_row = mask.empty() ? nullptr : mask.pixel(0, y);
    float* dst = padded + std::size_t(radius) * stride;
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
    // Clamped borders: copies of the first and last pixel.
    for (int i = 0; i < radius; ++i) {
        std::copy_n(padded + std::size_t(radius) * stride, stride, padded + std::size_t(i) * stride);
        std::copy_n(padded + std::size_t(radius + w - 1) * stride,
                    stride,
                    padded + std::size_t(radius + w + i) * stride);
    }
}

// One output pixel of a horizontal pass: the taps of `kernel` over `src` (the padded row at the
// pixel's leftmost tap), accumulated as convolve_row() does. Fixed channel counts let the
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
    // Enough for the images refined in parallel; at most 4 x 16 MB stay allocated (4 MB per
    // buffer in the main job: a 512^2 image with 4 weighted channels).
    static constexpr std::size_t kKept = 4;
    static constexpr std::size_t kLargestKept = std::size_t(1) << 22;  // floats
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

// The source pixels and weights one axis of resize_bilinear() reads for each output coordinate.
struct BilinearTaps {
    std::vector<int> first, second;  // source indices per output coordinate
    std::vector<float> t;            // weight of `second`
};

BilinearTaps bilinear_taps(int source_size, int size) {
    BilinearTaps taps;
    const float s = float(source_size) / float(size);
    for (int o = 0; o < size; ++o) {
        const float f = std::clamp((float(o) + 0.5f) * s - 0.5f, 0.0f, float(source_size - 1));
        const int i = std::min(int(f), source_size - 1);
        taps.first.push_back(i);
        taps.second.push_back(std::min(i + 1, source_size - 1));
        taps.t.push_back(f - float(i));
    }
    return taps;
}
}  // namespace

Image gaussian_blur_masked(const Image& image, const Image& mask, float sigma) {
    if (sigma <= 0.0f) return image;
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(mask.empty() || (mask.width() == w && mask.height() == h && mask.channels() == 1));
    const std::vector<float> kernel = gaussian_kernel(sigma);
    const int radius = int(kernel.size() / 2);
    const int stride = c + 1;  // weighted channels, then the weight
    const std::size_t row = std::size_t(w) * std::size_t(stride);
    // Horizontal pass over the weighted image, built row by row (no full-size weighted copy).
    ScratchBuffer horizontal(row * std::size_t(h));
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        std::vector<float> padded(std::size_t(w + 2 * radius) * std::size_t(stride));
        for (std::size_t y = y0; y < y1; ++y) {
            weighted_padded_row(image, mask, int(y), radius, padded.data());
            convolve_row(padded.data(), kernel, int(row), stride, horizontal.data() + y * row);
        }
    });
    // Vertical pass row by row (whole rows at a time, so it vectorises), then the division.
    Image out = image;
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        std::vector<float> sum(row);
        std::vector<const float*> sources(kernel.size());
        for (int y = int(y0); y < int(y1); ++y) {
            for (int k = -radius; k <= radius; ++k)
                sources[std::size_t(k + radius)] =
                    horizontal.data() + std::size_t(std::clamp(y + k, 0, h - 1)) * row;
            weighted_sum(sources.data(), kernel.data(), kernel.size(), row, sum.data());
            for (int x = 0; x < w; ++x) {
                const float* s = sum.data() + std::size_t(x) * std::size_t(stride);
                if (s[c] <= 0.0f) continue;
                float* dst = out.pixel(x, y);
                for (int ch = 0; ch < c; ++ch) dst[ch] = s[ch] / s[c];
            }
        }
    });
    return out;
}

Image gaussian_blur_resized(const Image& image, const Image& mask, float sigma, int width, int height) {
    if (sigma <= 0.0f) return resize_bilinear(image, width, height);
    TDF_CHECK(width > 0 && height > 0 && !image.empty());
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(mask.empty() || (mask.width() == w && mask.height() == h && mask.channels() == 1));
    const std::vector<float> kernel = gaussian_kernel(sigma);
    const int radius = int(kernel.size() / 2);
    const int stride = c + 1;
    const BilinearTaps tx = bilinear_taps(w, width), ty = bilinear_taps(h, height);

    // The blurred pixels the bilinear lookup reads: columns `cols` x rows `rows` (sorted, unique).
    const auto unique_sorted = [](const BilinearTaps& taps) {
        std::vector<int> v = taps.first;
        v.insert(v.end(), taps.second.begin(), taps.second.end());
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
        for (int k = -radius; k <= radius; ++k) row_needed[std::size_t(std::clamp(y + k, 0, h - 1))] = 1;

    // Horizontal pass at the needed columns of the needed rows.
    const std::size_t hrow = cols.size() * std::size_t(stride);
    ScratchBuffer horizontal(hrow * std::size_t(h));
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        std::vector<float> padded(std::size_t(w + 2 * radius) * std::size_t(stride));
        for (std::size_t y = y0; y < y1; ++y) {
            if (!row_needed[y]) continue;
            weighted_padded_row(image, mask, int(y), radius, padded.data());
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
                                       std::size_t(std::clamp(rows[i] + k, 0, h - 1)) * hrow +
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
        const float* top_row =
            blurred.data() + std::size_t(row_slot[std::size_t(ty.first[std::size_t(y)])]) * brow;
        const float* bottom_row =
            blurred.data() + std::size_t(row_slot[std::size_t(ty.second[std::size_t(y)])]) * brow;
        const float wy = ty.t[std::size_t(y)];
        for (int x = 0; x < width; ++x) {
            const std::size_t a =
                std::size_t(col_slot[std::size_t(tx.first[std::size_t(x)])]) * std::size_t(c);
            const std::size_t b =
                std::size_t(col_slot[std::size_t(tx.second[std::size_t(x)])]) * std::size_t(c);
            const float wx = tx.t[std::size_t(x)];
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

Image downsample_half(const Image& image) {
    const int w = (image.width() + 1) / 2, h = (image.height() + 1) / 2, c = image.channels();
    Image out(w, h, c);
    for (int y = 0; y < h; ++y)
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
    return out;
}

Image resize_bilinear(const Image& image, int width, int height) {
    TDF_CHECK(width > 0 && height > 0 && !image.empty());
    const int c = image.channels();
    Image out(width, height, c);
    const float sx = float(image.width()) / float(width), sy = float(image.height()) / float(height);
    parallel_for(std::size_t(height), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y) {
            const float fy = std::clamp((float(y) + 0.5f) * sy - 0.5f, 0.0f, float(image.height() - 1));
            const int iy = std::min(int(fy), image.height() - 1);
            const int iy1 = std::min(iy + 1, image.height() - 1);
            const float ty = fy - float(iy);
            for (int x = 0; x < width; ++x) {
                const float fx = std::clamp((float(x) + 0.5f) * sx - 0.5f, 0.0f, float(image.width() - 1));
                const int ix = std::min(int(fx), image.width() - 1);
                const int ix1 = std::min(ix + 1, image.width() - 1);
                const float tx = fx - float(ix);
                float* dst = out.pixel(x, y);
                for (int ch = 0; ch < c; ++ch) {
                    const float top = image.at(ix, iy, ch) * (1 - tx) + image.at(ix1, iy, ch) * tx;
                    const float bottom = image.at(ix, iy1, ch) * (1 - tx) + image.at(ix1, iy1, ch) * tx;
                    dst[ch] = top * (1 - ty) + bottom * ty;
                }
            }
        }
    });
    return out;
}

}  // namespace tdf
