#include <tdf/train/albedo_range.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/mesh/uv_seams.h>
#include <tdf/train/texel_atlas.h>

#include <algorithm>

namespace tdf {

std::vector<int> atlas_texel_charts(const TexelAtlas& atlas, const TriangleMesh& mesh) {
    const std::vector<int> chart_of_face = uv_charts(mesh, shared_edges(mesh));
    std::vector<int> label(atlas.texel_count(), -1);
    for (std::uint32_t t : atlas.texels) {
        const int face = atlas.raster.triangle[t];
        if (face >= 0) label[t] = chart_of_face[std::size_t(face)];
    }
    return label;
}

ColourRange local_colour_range(const Image& image, const std::vector<int>& label, int radius) {
    const int w = image.width(), h = image.height(), channels = image.channels();
    TDF_CHECK(label.size() == image.pixel_count());
    TDF_CHECK(radius >= 0);
    ColourRange range{image, image};
    // A direct window per texel rather than separable min/max passes: the window stops at the
    // chart's border, which a separable filter cannot follow. Once per run: (2r+1)^2 reads a texel.
    parallel_for(std::size_t(h), 8, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t t = std::size_t(y) * std::size_t(w) + std::size_t(x);
                const int own = label[t];
                if (own < 0) continue;
                float* low = range.low.data() + t * std::size_t(channels);
                float* high = range.high.data() + t * std::size_t(channels);
                for (int v = std::max(0, y - radius); v <= std::min(h - 1, y + radius); ++v)
                    for (int u = std::max(0, x - radius); u <= std::min(w - 1, x + radius); ++u) {
                        const std::size_t s = std::size_t(v) * std::size_t(w) + std::size_t(u);
                        if (label[s] != own) continue;
                        const float* value = image.data() + s * std::size_t(channels);
                        for (int c = 0; c < channels; ++c) {
                            low[c] = std::min(low[c], value[c]);
                            high[c] = std::max(high[c], value[c]);
                        }
                    }
            }
    });
    return range;
}

RangeExcess measure_range_excess(const Image& albedo, const ColourRange& input_range, const std::vector<int>& label,
                                 int radius, double limit) {
    TDF_CHECK(albedo.width() == input_range.high.width() && albedo.height() == input_range.high.height());
    TDF_CHECK(albedo.channels() == input_range.high.channels());
    TDF_CHECK(label.size() == albedo.pixel_count());
    RangeExcess e;
    e.limit = limit, e.radius = radius;
    const int channels = albedo.channels();
    std::size_t labelled = 0, above = 0, below = 0;
    for (std::size_t t = 0; t < label.size(); ++t) {
        if (label[t] < 0) continue;
        ++labelled;
        double over = 0, under = 0;
        for (int c = 0; c < channels; ++c) {
            const std::size_t i = t * std::size_t(channels) + std::size_t(c);
            over = std::max(over, double(albedo.data()[i]) - double(input_range.high.data()[i]));
            under = std::max(under, double(input_range.low.data()[i]) - double(albedo.data()[i]));
        }
        e.max_above = std::max(e.max_above, over);
        e.max_below = std::max(e.max_below, under);
        above += over > limit;
        below += under > limit;
    }
    if (labelled > 0) {
        e.fraction_above = double(above) / double(labelled);
        e.fraction_below = double(below) / double(labelled);
    }
    return e;
}

Json RangeExcess::to_json() const {
    return {{"max_above_local_max", max_above},     {"max_below_local_min", max_below},
            {"fraction_above_limit", fraction_above}, {"fraction_below_limit", fraction_below},
            {"limit", limit},                        {"radius_texels", radius}};
}

}  // namespace tdf
