#include <tdf/train/tactile_roundtrip.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/io/image_io.h>
#include <tdf/render/virtual_gelsight.h>
#include <tdf/tactile/normal_map.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/tactile/touch_comparison.h>

#include <algorithm>

namespace tdf {

Json tactile_roundtrip(const std::string& folder, const SceneAssets& assets, const ExportScale& scale,
                       std::uint64_t seed) {
    if (!(scale.mm_per_texel > 0) || !(scale.capture_mm_per_pixel > 0) || assets.description.tactile_images.empty())
        return Json();
    const std::unique_ptr<ReliefAsset> asset = load_relief_asset(folder);
    GelSightPad pad;
    pad.mm_per_pixel = scale.capture_mm_per_pixel;
    pad.width = pad.height = std::min(scale.capture_width, scale.capture_height);
    const std::vector<TouchPoint> candidates =
        random_touch_points(asset->mesh, 4 * kRoundTripTouches, seed ^ 0x544f554348ULL);  // "TOUCH"
    std::vector<SimulatedTouch> touches;
    Json uvs = Json::array();
    for (const TouchPoint& p : candidates) {
        if (int(touches.size()) == kRoundTripTouches) break;
        // Shrink the pad until it fits the part (it stays smaller for the points after).
        while (true) {
            try {
                touches.push_back(simulate_touch(*asset, p, pad));
                uvs.push_back({p.uv.x, p.uv.y});
                break;
            } catch (const Error&) {
                if (pad.width * 3 / 4 < 32) break;  // this point does not take even a small pad
                pad.width = pad.height = pad.width * 3 / 4;
            }
        }
    }
    if (touches.empty()) {
        log_warning("{}: no point of the asset takes a {} px virtual GelSight pad: no tactile round trip", folder, 32);
        return Json();
    }
    // Every touch at the final pad size, so that all are measured alike.
    std::vector<ReliefMeasure> measures;
    std::vector<Image> details;  // what the page shows: the touch with the object's form taken out
    for (SimulatedTouch& t : touches) {
        const int x0 = (t.height.height.width() - pad.width) / 2, y0 = (t.height.height.height() - pad.height) / 2;
        Image cropped(pad.width, pad.height, 1);
        for (int y = 0; y < pad.height; ++y)
            for (int x = 0; x < pad.width; ++x) cropped.at(x, y, 0) = t.height.height.at(x0 + x, y0 + y, 0);
        measures.push_back(measure_relief(cropped, pad.mm_per_pixel));
        details.push_back(gelsight_preview(normals_from_height(remove_quadratic(cropped), 1.0f / pad.mm_per_pixel)));
    }
    const TactileMap capture = load_tactile_map(assets.description.tactile_images.front());
    const TouchRoundTrip r = compare_touches(measure_capture(capture.normals, scale.capture_mm_per_pixel, pad.width), measures);
    const std::string touch_folder = folder + "/touch";
    ensure_folder(touch_folder);
    // The capture's centre at the pad's size: side by side at the same scale (pixels of one pitch).
    const int cx = std::max(0, (capture.normals.width() - pad.width) / 2);
    const int cy = std::max(0, (capture.normals.height() - pad.height) / 2);
    const int cw = std::min(pad.width, capture.normals.width()), ch = std::min(pad.height, capture.normals.height());
    Image centre(cw, ch, 3);
    for (int y = 0; y < ch; ++y)
        for (int x = 0; x < cw; ++x)
            for (int c = 0; c < 3; ++c) centre.at(x, y, c) = capture.normals.at(cx + x, cy + y, c);
    write_png(touch_folder + "/capture_gelsight.png", gelsight_preview(centre), 8, Quantize::Round);
    for (std::size_t k = 0; k < touches.size(); ++k)
        write_png(fmt::format("{}/touch_{:03d}_gelsight.png", touch_folder, k), details[k], 8, Quantize::Round);
    Json j = r.to_json();
    j["pad"] = {{"width", pad.width}, {"height", pad.height}, {"mm_per_pixel", pad.mm_per_pixel}};
    j["touch_uvs"] = uvs;
    j["within_aim"] = r.tilt_ratio >= kRoundTripMinRatio && r.tilt_ratio <= kRoundTripMaxRatio &&
                      r.height_rms_ratio >= kRoundTripMinRatio && r.height_rms_ratio <= kRoundTripMaxRatio;
    log_info("tactile round trip ({} touches, {} px pad): tilt ratio {:.3f}, height RMS ratio {:.3f}, spectrum "
             "distance {:.3f}",
             touches.size(), pad.width, r.tilt_ratio, r.height_rms_ratio, r.spectrum_distance);
    return j;
}

}  // namespace tdf
