#include <tdf/tactile/ambient_occlusion.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>

#include <algorithm>
#include <cmath>

namespace tdf {

Image ambient_occlusion(const Image& height, float texel_size, bool periodic, const std::vector<int>& region) {
    TDF_CHECK(height.channels() == 1 && texel_size > 0);
    const int w = height.width(), h = height.height();
    TDF_CHECK(region.empty() || region.size() == height.pixel_count());
    // Each direction's march as whole-texel offsets, precomputed once (no trig per texel).
    struct Step {
        int dx, dy;
        float distance;
    };
    std::vector<Step> steps;
    for (int k = 0; k < kAoDirections; ++k) {
        const double angle = 2.0 * 3.14159265358979323846 * k / kAoDirections;
        for (int t = 1; t <= kAoRadiusTexels; ++t) {
            const int dx = int(std::lround(t * std::cos(angle))), dy = int(std::lround(t * std::sin(angle)));
            steps.push_back({dx, dy, float(std::sqrt(double(dx * dx + dy * dy))) * texel_size});
        }
    }
    Image out(w, h, 1);
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t here = std::size_t(y) * std::size_t(w) + std::size_t(x);
                const int own = region.empty() ? 0 : region[here];
                if (own < 0) {
                    out.at(x, y, 0) = 1.0f;
                    continue;
                }
                const float h0 = height.data()[here];
                float occlusion = 0;
                for (int k = 0; k < kAoDirections; ++k) {
                    float highest = 0;  // tangent of the horizon's elevation
                    for (int t = 0; t < kAoRadiusTexels; ++t) {
                        const Step& s = steps[std::size_t(k * kAoRadiusTexels + t)];
                        int qx = x + s.dx, qy = y + s.dy;
                        if (periodic) {
                            qx = ((qx % w) + w) % w, qy = ((qy % h) + h) % h;
                        } else if (qx < 0 || qy < 0 || qx >= w || qy >= h) {
                            break;
                        }
                        const std::size_t q = std::size_t(qy) * std::size_t(w) + std::size_t(qx);
                        if (!region.empty() && region[q] != own) break;
                        highest = std::max(highest, (height.data()[q] - h0) / s.distance);
                    }
                    occlusion += highest / std::sqrt(1.0f + highest * highest);  // sine of the horizon
                }
                out.at(x, y, 0) = 1.0f - occlusion / float(kAoDirections);
            }
    });
    return out;
}

}  // namespace tdf
