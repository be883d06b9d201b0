#pragma once
/// Where to look at the albedo (issue 29): the run report shows the input, after-matching and
/// final albedo side by side at the input's darkest and brightest spot, the places where light
/// painted into the albedo shows first (a dark colour turned grey, a highlight on a light one).
#include <tdf/core/image.h>

#include <string>
#include <vector>

namespace tdf {

struct AlbedoSpot {
    std::string name;  ///< "dark" or "bright"
    int x = 0, y = 0;  ///< top-left texel of the window
    int size = 0;      ///< window side, texels
    double luminance = 0;  ///< mean input luminance over the window
};

/// The darkest and the brightest window (side `size` texels, searched on a grid of size / 4)
/// of `input` (RGB) among the windows whose texels all have `label >= 0` and one label (one
/// chart: a crop across a seam shows two unrelated surface pieces). Fewer than two spots when no
/// window qualifies (a tiny or fragmented atlas).
std::vector<AlbedoSpot> find_albedo_spots(const Image& input, const std::vector<int>& label, int size);

/// The spot's window of `map` (RGB, the size of the input the spot was found in): what the strip
/// shows of it, so a run keeps the after-matching albedo's two crops, not the whole map.
Image albedo_spot_crop(const AlbedoSpot& spot, const Image& map);

/// One strip per spot: input | after matching | final, three crops of one spot
/// (albedo_spot_crop), each scaled `zoom` x with nearest texels (so texels stay visible), clamped
/// to [0, 1], with 4 white pixels between them.
Image albedo_spot_strip(const Image& input_crop, const Image& matched_crop, const Image& final_crop, int zoom);

}  // namespace tdf
