#include <tdf/train/part_quality.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/part_target.h>
#include <tdf/tactile/material_statistics.h>
#include <tdf/train/texture_bake.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

Vec3f unit_texel(const Image& image, std::size_t t) {
    const float* p = image.data() + 3 * t;
    return safe_normalize(Vec3f{p[0], p[1], p[2]});
}

}  // namespace

std::vector<PartQuality> measure_part_quality(const Image& normal_map, const Image& target,
                                              const std::vector<int>& truth, const std::vector<int>& predicted,
                                              int size, const std::vector<Image>& layers,
                                              const std::vector<std::string>& names) {
    const std::size_t texel_count = std::size_t(size) * std::size_t(size);
    TDF_CHECK_EQ(truth.size(), texel_count);
    TDF_CHECK_EQ(normal_map.pixel_count(), texel_count);
    TDF_CHECK_EQ(target.pixel_count(), texel_count);
    TDF_CHECK_EQ(layers.size(), names.size());
    TDF_CHECK(predicted.empty() || predicted.size() == texel_count);
    const PartBoundaryMeasure boundary = measure_part_boundary(normal_map, truth, size, layers);
    // The target, not the bare layer, is the reference for the tilt: it has the same gutter
    // and background as the learned map, so the high-pass sees the same chart borders in both.
    const DetailSlopes learned = detail_slopes(normal_map), wanted = detail_slopes(target);
    std::vector<PartQuality> out(names.size());
    std::vector<double> tilt(names.size(), 0.0), tilt_wanted(names.size(), 0.0);
    std::vector<std::size_t> right(names.size(), 0);
    for (std::size_t t = 0; t < texel_count; ++t) {
        const int p = truth[t];
        if (p < 0) continue;
        PartQuality& q = out[std::size_t(p)];
        ++q.texels;
        right[std::size_t(p)] += !predicted.empty() && predicted[t] == p;
        q.normal_cosine += double(dot(unit_texel(normal_map, t), unit_texel(layers[std::size_t(p)], t)));
        tilt[std::size_t(p)] += double(learned.tilt.data()[t]);
        tilt_wanted[std::size_t(p)] += double(wanted.tilt.data()[t]);
    }
    for (std::size_t k = 0; k < out.size(); ++k) {
        PartQuality& q = out[k];
        q.name = names[k];
        q.bleed_texels = boundary.part_bleed_texels[k];
        if (q.texels == 0) continue;
        q.label_accuracy = double(right[k]) / double(q.texels);
        q.normal_cosine /= double(q.texels);
        q.tilt_ratio = tilt_wanted[k] > 0 ? tilt[k] / tilt_wanted[k] : 0.0;
    }
    return out;
}

Json part_quality_json(const std::vector<PartQuality>& final, const std::vector<PartQuality>& after_matching) {
    Json parts = Json::array();
    for (std::size_t k = 0; k < final.size(); ++k) {
        const PartQuality& q = final[k];
        parts.push_back({{"name", q.name},
                         {"texels", q.texels},
                         {"label_accuracy", q.label_accuracy},
                         {"bleed_texels", after_matching.empty() ? q.bleed_texels : after_matching[k].bleed_texels},
                         {"tilt_ratio", q.tilt_ratio},
                         {"normal_cosine", q.normal_cosine}});
    }
    return parts;
}

Json write_part_report_entries(const std::string& base, const std::vector<PartQuality>& final,
                               const std::vector<PartQuality>& after_matching, const std::vector<Image>& layers) {
    TDF_CHECK_EQ(layers.size(), final.size());
    Json parts = part_quality_json(final, after_matching);
    const std::string stem = base.substr(base.find_last_of('/') + 1);
    for (std::size_t k = 0; k < final.size(); ++k) {
        const Image& layer = layers[k];
        const int side = std::min({128, layer.width(), layer.height()});
        Image swatch(side, side, 3);
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x)
                for (int c = 0; c < 3; ++c) swatch.at(x, y, c) = layer.at(x, y, c);
        const std::string swatch_name = stem + "_swatch_" + final[k].name + ".png";
        const Image encoded = encode_normal_map(swatch);
        write_atomically(base + "_swatch_" + final[k].name + ".png",
                         [&](const std::string& tmp) { write_png(tmp, encoded, 8, Quantize::Truncate); });
        const Vec3f c = part_colour(int(k));
        parts[k]["colour"] = fmt::format("#{:02x}{:02x}{:02x}", int(std::lround(c.x * 255)),
                                         int(std::lround(c.y * 255)), int(std::lround(c.z * 255)));
        parts[k]["mask"] = stem + "_mask_" + final[k].name + ".png";
        parts[k]["swatch"] = swatch_name;
    }
    return parts;
}

}  // namespace tdf
