#include <tdf/tactile/normal_map.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/tactile/poisson.h>

#include <algorithm>
#include <cmath>

namespace tdf {

float reference_amplitude_factor(float scale_mm) {
    if (scale_mm > 20.0f) return 1.25f;
    if (scale_mm > 10.0f) return 1.5f;
    if (scale_mm > 5.0f) return 3.0f;
    return 5.0f;
}

Image normals_from_height(const Image& height, float gain, bool wrap) {
    TDF_CHECK_EQ(height.channels(), 1);
    const int w = height.width(), h = height.height();
    if (w < 3 || h < 3) throw_error("a {}x{} height map is too small for normals (at least 3x3)", w, h);
    Image normals(w, h, 3);
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y) {
            // Borders copy the nearest interior gradient (reference), or wrap around.
            const int r = wrap ? y : std::clamp(y, 1, h - 2);
            const int up = wrap ? (r + h - 1) % h : r - 1, down = wrap ? (r + 1) % h : r + 1;
            for (int x = 0; x < w; ++x) {
                const int c = wrap ? x : std::clamp(x, 1, w - 2);
                const int left = wrap ? (c + w - 1) % w : c - 1, right = wrap ? (c + 1) % w : c + 1;
                const float gx = -gain * (height.at(right, r, 0) - height.at(left, r, 0)) * 0.5f;
                const float gy = gain * (height.at(c, down, 0) - height.at(c, up, 0)) * 0.5f;  // row up is up
                const float inv = 1.0f / std::sqrt(gx * gx + gy * gy + 1.0f);
                float* n = normals.pixel(x, y);
                n[0] = gx * inv;
                n[1] = gy * inv;
                n[2] = inv;
            }
        }
    });
    return normals;
}

Image height_from_normals(const Image& normals, float min_nz, const std::string& what) {
    TDF_CHECK(normals.channels() >= 3);
    const int w = normals.width(), h = normals.height();
    Image gx(w, h, 1), gy(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float* n = normals.pixel(x, y);
            const float nz = std::max(n[2], min_nz);
            gx.at(x, y, 0) = -n[0] / nz;
            gy.at(x, y, 0) = n[1] / nz;  // green up: height grows towards row 0 when ny > 0
        }
    return integrate_gradients(gx, gy, what);
}

Image scale_normal_slopes(const Image& normals, float factor) {
    TDF_CHECK(normals.channels() >= 3);
    Image out(normals.width(), normals.height(), 3);
    for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
        const float* n = normals.data() + p * std::size_t(normals.channels());
        const float nz = std::max(n[2], 1e-3f);
        const float sx = factor * n[0] / nz, sy = factor * n[1] / nz;
        const float inv = 1.0f / std::sqrt(sx * sx + sy * sy + 1.0f);
        float* o = out.data() + 3 * p;
        o[0] = sx * inv, o[1] = sy * inv, o[2] = inv;
    }
    return out;
}

Image encode_normals(const Image& normals) {
    Image out = normals;
    for (float& v : out.values()) v = v * 0.5f + 0.5f;
    return out;
}

}  // namespace tdf
