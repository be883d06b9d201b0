// What leaves the trainer for export: the maps as they are now, the label head's parts per texel,
// and how far an albedo leaves the input's local colour range.
// Reads: the learned maps (texture evaluation) or the field (pixel evaluation, baked), the atlas,
// the label head. Writes nothing in the trainer.
#include "trainer_impl.h"

#include <tdf/core/error.h>
#include <tdf/train/part_label_head.h>

namespace tdf {

using namespace trainer_detail;

RangeExcess Trainer::albedo_range_excess(const Image& albedo) const {
    TDF_CHECK(texture_space());
    const ColourRange input = local_colour_range(albedo_target(), m_texel_charts, kRangeMeasureRadius);
    return measure_range_excess(albedo, input, m_texel_charts, kRangeMeasureRadius, kRangeMeasureLimit);
}

BakedMaps Trainer::export_maps() const {
    if (!texture_space()) return bake_field(*m_field, *m_target.mesh, m_config.texture_size, m_config.gutter);
    TDF_CHECK(m_maps_ready);
    BakedMaps maps;
    maps.albedo = m_maps->export_albedo();
    maps.tactile_normal = m_maps->export_normal();
    // Export reads only which texels are covered: the barycentrics (12 bytes a texel) stay behind.
    maps.raster.size = m_atlas->raster.size;
    maps.raster.triangle = m_atlas->raster.triangle;
    return maps;
}

std::vector<int> Trainer::predicted_texel_parts() const {
    if (!m_label_head) return {};
    const TexelAtlas& atlas = *m_atlas;
    const std::vector<int> predicted = m_label_head->predict(*m_field, atlas.points.data(), atlas.points.size());
    std::vector<int> labels(atlas.texel_count(), -1);
    for (std::size_t k = 0; k < predicted.size(); ++k) labels[atlas.texels[k]] = predicted[k];
    return labels;
}

}  // namespace tdf
