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

Image normals_from_height(const Image& height, float gain) {
    TDF_CHECK_EQ(height.channels(), 1);
    const int w = height.width(), h = height.height();
    if (w < 3 || h < 3) throw_error("a {}x{} height map is too small for normals (at least 3x3)", w, h);
    Image normals(w, h, 3);
    parallel_for(std::size_t(h), 16, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y) {
            const int r = std::clamp(y, 1, h - 2);  // borders copy the nearest interior gradient
            for (int x = 0; x < w; ++x) {
                const int c = std::clamp(x, 1, w - 2);
                const float gx = -gain * (height.at(c + 1, r, 0) - height.at(c - 1, r, 0)) * 0.5f;
                const float gy =
                    gain * (height.at(c, r + 1, 0) - height.at(c, r - 1, 0)) * 0.5f;  // row r-1 is up
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

Image encode_normals(const Image& normals) {
    Image out = normals;
    for (float& v : out.values()) v = v * 0.5f + 0.5f;
    return out;
}

}  // namespace tdf
