#pragma once
/// The round trip of issue 24: after a run has exported its asset, a virtual GelSight presses it
/// at a few random points and what it measures is compared with the scene's tactile capture.
#include <tdf/core/config.h>
#include <tdf/render/scene_assets.h>
#include <tdf/tactile/height_export.h>

#include <cstdint>
#include <string>

namespace tdf {

/// Touches pressed per run.
constexpr int kRoundTripTouches = 4;

/// Presses kRoundTripTouches points (Rng(seed)) of the asset in `folder` (load_relief_asset)
/// with the capture's sensor (`scale`: its pitch, the smaller of its sides); where that pad is
/// larger than the part, the pad shrinks by 3/4 steps down to 32 pixels, and points where even
/// that misses are drawn again (at most 4 x as many draws). Compares them with the scene's
/// first tactile image (measure_capture at its pitch, over pad-sized windows). Writes
/// `<folder>/touch/capture_gelsight.png` (the capture's centre, pad-sized) and
/// `touch_<k>_gelsight.png` (each touch with its quadratic form removed, as measured): the
/// report's side by side, at one scale. Multi-part scenes compare with the first part's map
/// only. Returns TouchRoundTrip::to_json()
/// plus the pad used and the touches' UVs; null when there is nothing to press.
Json tactile_roundtrip(const std::string& folder, const SceneAssets& assets, const ExportScale& scale,
                       std::uint64_t seed);

}  // namespace tdf
