#pragma once
// Tangent-space normals of a tileable height field for the scene generators in tools/: OpenGL
// convention (green = +v = up the image), central differences with wrap-around, `strength`
// scaling the slopes, stored as (n + 1) / 2 (write_png truncates when it quantises).
#include <tdf/core/image.h>
#include <tdf/core/vec.h>

namespace tdf::tools {

inline Image tileable_normal_map(const Image& height, float strength) {
    const int n = height.width();
    Image out(n, n, 3);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const float dhdu = 0.5f * (height.at((x + 1) % n, y, 0) - height.at((x + n - 1) % n, y, 0));
            // Rows grow downward, v grows upward.
            const float dhdv = -0.5f * (height.at(x, (y + 1) % n, 0) - height.at(x, (y + n - 1) % n, 0));
            const Vec3f nrm = safe_normalize({-strength * dhdu, -strength * dhdv, 1.f});
            for (int c = 0; c < 3; ++c) out.at(x, y, c) = nrm[c] * 0.5f + 0.5f;
        }
    return out;
}

}  // namespace tdf::tools
