#include <tdf/atlas/gutter.h>
#include <tdf/core/error.h>

#include <cstdint>

namespace tdf {

void dilate_gutter(Image& image, const std::vector<int>& coverage, int texels) {
    const int w = image.width(), h = image.height(), channels = image.channels();
    if (coverage.size() != image.pixel_count())
        throw_error("gutter dilation: coverage has {} entries for a {}x{} image", coverage.size(), w, h);
    std::vector<std::uint8_t> filled(coverage.size());
    for (std::size_t i = 0; i < coverage.size(); ++i) filled[i] = coverage[i] >= 0 ? 1 : 0;

    // The first frontier: empty texels touching a covered one. Later frontiers are built from
    // the texels filled in the previous pass, so the total cost is proportional to what is filled.
    std::vector<int> frontier, next;
    std::vector<std::uint8_t> queued(coverage.size(), 0);
    const auto push_empty_neighbours = [&](int x, int y, std::vector<int>& out) {
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int nx = x + dx, ny = y + dy;
                if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
                const int n = ny * w + nx;
                if (filled[std::size_t(n)] || queued[std::size_t(n)]) continue;
                queued[std::size_t(n)] = 1;
                out.push_back(n);
            }
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (filled[std::size_t(y * w + x)]) {
                // Only covered texels on the region's edge can have empty neighbours.
                push_empty_neighbours(x, y, frontier);
            }

    std::vector<float> values;
    std::vector<float> sum(std::size_t(channels), 0.0f);
    for (int pass = 0; !frontier.empty() && (texels <= 0 || pass < texels); ++pass) {
        // Compute every frontier value from the texels filled before this pass, then commit.
        values.assign(frontier.size() * std::size_t(channels), 0.0f);
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            const int x = frontier[k] % w, y = frontier[k] / w;
            std::fill(sum.begin(), sum.end(), 0.0f);
            float weight = 0.0f;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int nx = x + dx, ny = y + dy;
                    if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
                    if (!filled[std::size_t(ny * w + nx)]) continue;
                    const float wt = (dx == 0 || dy == 0) ? 2.0f : 1.0f;
                    const float* p = image.pixel(nx, ny);
                    for (int c = 0; c < channels; ++c) sum[std::size_t(c)] += wt * p[c];
                    weight += wt;
                }
            TDF_CHECK(weight > 0.0f);
            for (int c = 0; c < channels; ++c)
                values[k * std::size_t(channels) + std::size_t(c)] = sum[std::size_t(c)] / weight;
        }
        for (std::size_t k = 0; k < frontier.size(); ++k) {
            float* p = image.pixel(frontier[k] % w, frontier[k] / w);
            for (int c = 0; c < channels; ++c) p[c] = values[k * std::size_t(channels) + std::size_t(c)];
            filled[std::size_t(frontier[k])] = 1;
        }
        next.clear();
        for (const int t : frontier) push_empty_neighbours(t % w, t / w, next);
        frontier.swap(next);
    }
}

}  // namespace tdf
