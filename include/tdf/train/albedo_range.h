#pragma once
/// The input albedo's local colour range over the atlas (issue 29): what "dark stays dark,
/// saturated stays saturated" means texel by texel. The refinement may add colour variation that
/// follows the relief, but a texel must not leave the range of colours its own neighbourhood had in
/// the input by more than a stated tolerance; otherwise a guidance target that carries light (a
/// highlight, a shaded render divided by the wrong shade) is painted into the albedo, and a viewer
/// that lights the asset again shows that light twice.
///
/// One implementation for the trainer's bound (LearnedMaps::set_albedo_bounds) and for the
/// report's measure (measure_range_excess), so the two agree on what a neighbourhood is.
#include <tdf/core/image.h>
#include <tdf/core/config.h>
#include <tdf/mesh/triangle_mesh.h>

#include <cstdint>
#include <vector>

namespace tdf {

struct TexelAtlas;

/// Per texel and channel, the smallest and largest value of an image over a neighbourhood.
struct ColourRange {
    Image low, high;
};

/// The neighbourhood label of every texel of `atlas`: the UV chart (uv_charts) of the face that
/// covers it, -1 for gutter texels. Two texels side by side in the atlas but on different charts
/// are far apart on the surface, so they are not each other's neighbours.
std::vector<int> atlas_texel_charts(const TexelAtlas& atlas, const TriangleMesh& mesh);

/// Per texel with `label[t] >= 0`, per channel: min and max of `image` over the texels of the
/// same label in the (2 radius + 1)^2 window around it. Texels with label -1 get their own value
/// as both. `label` has one entry per pixel of `image`; radius >= 0. Parallel over rows,
/// deterministic.
ColourRange local_colour_range(const Image& image, const std::vector<int>& label, int radius);

/// How far a learned albedo leaves the input's local range, over texels with label >= 0.
struct RangeExcess {
    /// Largest amount by which a channel exceeds its local max (brighter than anything near it
    /// in the input) / falls below its local min; 0 when inside.
    double max_above = 0, max_below = 0;
    /// Fraction of labelled texels with any channel more than `limit` above / below.
    double fraction_above = 0, fraction_below = 0;
    double limit = 0;
    int radius = 0;
    Json to_json() const;
};

RangeExcess measure_range_excess(const Image& albedo, const ColourRange& input_range, const std::vector<int>& label,
                                 int radius, double limit);

/// The measure's neighbourhood (texels at the map size) and the issue's limit for "no added
/// pixel brighter than the input's local maximum + 0.05".
constexpr int kRangeMeasureRadius = 4;
constexpr double kRangeMeasureLimit = 0.05;

}  // namespace tdf
