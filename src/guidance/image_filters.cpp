#include <tdf/guidance/image_filters.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>
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

// One 1D pass (horizontal when `horizontal`) over a weighted image: `values` holds w*x per channel
// followed by w in the last channel.
Image blur_pass(const Image& values, const std::vector<float>& kernel, bool horizontal) {
    const int w = values.width(), h = values.height(), c = values.channels();
    const int radius = int(kernel.size() / 2);
    Image out(w, h, c);
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                float* dst = out.pixel(x, y);
                for (int k = -radius; k <= radius; ++k) {
                    const int sx = horizontal ? std::clamp(x + k, 0, w - 1) : x;
                    const int sy = horizontal ? y : std::clamp(y + k, 0, h - 1);
                    const float weight = kernel[std::size_t(k + radius)];
                    const float* src = values.pixel(sx, sy);
                    for (int ch = 0; ch < c; ++ch) dst[ch] += weight * src[ch];
                }
            }
    });
    return out;
}
}  // namespace

Image gaussian_blur_masked(const Image& image, const Image& mask, float sigma) {
    if (sigma <= 0.0f) return image;
    const int w = image.width(), h = image.height(), c = image.channels();
    TDF_CHECK(mask.empty() || (mask.width() == w && mask.height() == h && mask.channels() == 1));
    Image weighted(w, h, c + 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float m = mask.empty() ? 1.0f : mask.at(x, y, 0);
            float* dst = weighted.pixel(x, y);
            const float* src = image.pixel(x, y);
            for (int ch = 0; ch < c; ++ch) dst[ch] = m * src[ch];
            dst[c] = m;
        }
    const std::vector<float> kernel = gaussian_kernel(sigma);
    const Image blurred = blur_pass(blur_pass(weighted, kernel, true), kernel, false);
    Image out = image;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* src = blurred.pixel(x, y);
            if (src[c] <= 0.0f) continue;
            float* dst = out.pixel(x, y);
            for (int ch = 0; ch < c; ++ch) dst[ch] = src[ch] / src[c];
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
