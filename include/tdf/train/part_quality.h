#pragma once
/// Per-part quality of a multi-part run: what `<name>_report.json` holds under `parts[]` and the
/// report page shows per part (docs/multi-part-textures.md). Each measure is taken in texture
/// space over the texels of one part, so a part that picked up another part's relief, or whose
/// labels the head got wrong, shows in its own row.
#include <tdf/core/config.h>
#include <tdf/core/image.h>

#include <string>
#include <vector>

namespace tdf {

struct PartQuality {
    std::string name;
    std::size_t texels = 0;     ///< covered texels the segmentation gives the part
    double label_accuracy = 0;  ///< share of them the label head predicts as the part
    /// Farthest texel of the part (centre distance to another part) whose normal differs from
    /// the part's own laid map by more than 1 degree (measure_part_boundary, per part).
    double bleed_texels = 0;
    /// Mean detail tilt (material_statistics.h: slopes after a 12-texel high-pass) of the normal
    /// map over the part's texels, over the same of the composed tactile target (the part's own
    /// map laid with its layout): 1 = the part keeps its own relief's strength; another part's
    /// stronger or weaker relief leaking in moves it away from 1.
    double tilt_ratio = 0;
    double normal_cosine = 0;  ///< mean cosine of the normal map against the part's laid map
};

/// Measures every part. `normal_map` and `target` are size x size unit normals (the learned map
/// and compose_part_target's); `truth` the segmentation's texel parts (-1 = uncovered);
/// `predicted` the head's (empty = label accuracy not measured, left 0); `layers` each part's
/// laid map (lay_part_maps).
std::vector<PartQuality> measure_part_quality(const Image& normal_map, const Image& target,
                                              const std::vector<int>& truth, const std::vector<int>& predicted,
                                              int size, const std::vector<Image>& layers,
                                              const std::vector<std::string>& names);

/// The report's `parts[]`: per part `name`, `texels`, `label_accuracy`, `tilt_ratio`,
/// `normal_cosine` of `final`, and `bleed_texels` of `after_matching` (refinement changes texels
/// everywhere, so the final map's "bleed" would measure the guidance, not the labels).
/// `after_matching` may be empty (a run without refinement: then the final map's bleed).
Json part_quality_json(const std::vector<PartQuality>& final, const std::vector<PartQuality>& after_matching);

/// The report's `parts[]` for a run whose outputs are `<base>_*` (part_quality_json per part,
/// plus `colour` "#rrggbb" of the label map, `mask` = the `<name>_mask_<part>.png` that
/// write_part_maps wrote, and `swatch` = `<name>_swatch_<part>.png`, written here: a 128 x 128
/// corner of the part's laid map (`layers`), the relief the part should carry).
Json write_part_report_entries(const std::string& base, const std::vector<PartQuality>& final,
                               const std::vector<PartQuality>& after_matching, const std::vector<Image>& layers);

}  // namespace tdf
