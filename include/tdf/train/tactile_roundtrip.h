#pragma once
/// The round trip of issue 24: after a run has exported its asset, a virtual GelSight presses it
/// at a few random points and what it measures is compared with the scene's tactile capture.
#include <tdf/core/config.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/scene_file.h>
#include <tdf/tactile/height_export.h>

#include <cstdint>
#include <string>

namespace tdf {

/// Touches pressed per part.
constexpr int kRoundTripTouches = 8;

/// Presses kRoundTripTouches points of each part (drawn uniformly over the area from Rng(seed),
/// each part taking the points that land on it, at most 8 x as many draws as touches wanted) of
/// the asset in `folder` (load_relief_asset) with the capture's sensor (`scale`: its pitch, the
/// smaller of its sides); where that pad is larger than the part, the pad shrinks by 3/4 steps
/// down to 32 pixels, and a point where even that misses is skipped. Every touch is then measured
/// at the final pad size and compared with its own part's first tactile image (one-part scenes:
/// the scene's; measure_capture at the pad's pitch, over pad-sized windows). Writes
/// `<folder>/touch/capture_gelsight.png` (`capture_<part>_gelsight.png` per part: the capture's
/// centre, pad-sized) and `touch_<k>_gelsight.png` (each touch with its quadratic form removed,
/// as measured): the report's side by side, at one scale. Returns TouchRoundTrip::to_json() (with
/// several parts: the touch-weighted means of the parts' ratios, and `parts[]` with each part's
/// comparison) plus `touch_count`, the pad used, the touches' UVs and `within_aim` (every part's
/// ratios and the means in the aim); null when there is nothing to press.
Json tactile_roundtrip(const std::string& folder, const SceneAssets& assets, const PartsSpec& parts,
                       const ExportScale& scale, std::uint64_t seed);

}  // namespace tdf
