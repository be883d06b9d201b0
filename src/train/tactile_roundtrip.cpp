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
#include <cmath>

namespace tdf {

namespace {

/// What a touch is compared with: the part's name ("" for a one-part scene), its capture, and
/// the sensor pitch at which the capture's pixels lie on the asset.
struct PartCapture {
    std::string name, image;
    TactileMap map;
    float pitch_mm = 0;       // one capture pixel on the asset, mm
    float own_pitch_mm = 0;   // the capture's own pixel (metadata, the layout's, else GelSight Mini's)
    std::vector<TouchPoint> points;  // accepted touch points on this part
};

/// One-part scenes: the capture's pixel as the export scale took it. Parts: each part's map lies
/// on the atlas with its own layout; in atlas mode `repeat` times over the atlas, whose UV unit
/// spans `uv_mm` (the export's scale, from the scene's own map), so one of its pixels spans
/// uv_mm / (its size x repeat) there: a part laid finer than its capture is touched at a finer
/// pitch and its capture measured at that pitch (the relief the scene asked for, at its scale).
std::vector<PartCapture> part_captures(const SceneAssets& assets, const PartsSpec& parts, const ExportScale& scale,
                                       float uv_mm) {
    std::vector<PartCapture> captures;
    if (!parts.enabled()) {
        PartCapture c{"", assets.description.tactile_images.front(), {}, scale.capture_mm_per_pixel,
                      scale.capture_mm_per_pixel, {}};
        c.map = load_tactile_map(c.image);
        return {std::move(c)};
    }
    for (const PartSpec& p : parts.parts) {
        PartCapture c{p.name, p.tactile_images.front(), {}, 0, 0, {}};
        c.map = load_tactile_map(c.image);
        c.own_pitch_mm = p.layout.mm_per_pixel > 0 ? p.layout.mm_per_pixel
                         : c.map.mm_per_pixel > 0  ? c.map.mm_per_pixel
                                                   : kGelSightMiniMmPerPixel;
        const double side = std::sqrt(double(c.map.normals.width()) * double(c.map.normals.height()));
        c.pitch_mm = p.layout.mode == "physical" ? c.own_pitch_mm : float(double(uv_mm) / (side * double(p.layout.repeat)));
        captures.push_back(std::move(c));
    }
    return captures;
}

/// The part a face of the exported asset belongs to: its OBJ material (write_obj names each
/// part's material after the part), else the first.
std::size_t part_of_face(const TriangleMesh& mesh, int face, const std::vector<PartCapture>& captures) {
    if (captures.size() < 2 || mesh.face_group.empty()) return 0;
    const std::string& material = mesh.face_groups[std::size_t(mesh.face_group[std::size_t(face)])].material;
    for (std::size_t k = 0; k < captures.size(); ++k)
        if (captures[k].name == material) return k;
    return 0;
}

/// Whether every pixel of `touch` lies on part `k` (a touch across two parts would measure both
/// reliefs against one capture).
bool on_one_part(const TriangleMesh& mesh, const SimulatedTouch& touch, std::size_t k,
                 const std::vector<PartCapture>& captures) {
    if (captures.size() < 2) return true;
    return std::all_of(touch.triangles.begin(), touch.triangles.end(),
                       [&](int face) { return face >= 0 && part_of_face(mesh, face, captures) == k; });
}

/// Draws points until every part holds kRoundTripTouches that take the pad. A point where the
/// pad misses the mesh shrinks the pad by 3/4 (down to 32 px; it stays at its smallest); a point
/// whose pad crosses into another part is skipped. When a part ends with fewer than half its
/// touches (its region narrower than the pad), the pad shrinks and the drawing starts again.
void draw_touch_points(const ReliefAsset& asset, std::vector<PartCapture>& captures, int& pad_pixels,
                       std::uint64_t seed) {
    const int wanted = kRoundTripTouches * int(captures.size());
    const std::vector<TouchPoint> candidates =
        random_touch_points(asset.mesh, 8 * wanted, seed ^ 0x544f554348ULL);  // "TOUCH"
    while (true) {
        for (PartCapture& c : captures) c.points.clear();
        int accepted = 0;
        for (const TouchPoint& p : candidates) {
            if (accepted == wanted) break;
            const std::size_t k = part_of_face(asset.mesh, p.triangle, captures);
            PartCapture& part = captures[k];
            if (int(part.points.size()) == kRoundTripTouches) continue;
            while (true) {
                try {
                    const SimulatedTouch t = simulate_touch(asset, p, GelSightPad{pad_pixels, pad_pixels, part.pitch_mm});
                    if (on_one_part(asset.mesh, t, k, captures)) part.points.push_back(p), ++accepted;
                    break;
                } catch (const Error&) {
                    if (pad_pixels * 3 / 4 < 32) break;  // this point does not take even a small pad
                    pad_pixels = pad_pixels * 3 / 4;
                }
            }
        }
        const bool enough = std::all_of(captures.begin(), captures.end(), [](const PartCapture& c) {
            return 2 * int(c.points.size()) >= kRoundTripTouches;
        });
        if (enough || pad_pixels * 3 / 4 < 32) return;
        pad_pixels = pad_pixels * 3 / 4;
    }
}

/// One touch at the final pad size, as measured (the centre pad-sized crop), and what the page
/// shows of it (the form taken out).
ReliefMeasure measure_touch(const ReliefAsset& asset, const TouchPoint& p, const GelSightPad& pad, Image& preview) {
    const SimulatedTouch t = simulate_touch(asset, p, pad);
    const int x0 = (t.height.height.width() - pad.width) / 2, y0 = (t.height.height.height() - pad.height) / 2;
    Image cropped(pad.width, pad.height, 1);
    for (int y = 0; y < pad.height; ++y)
        for (int x = 0; x < pad.width; ++x) cropped.at(x, y, 0) = t.height.height.at(x0 + x, y0 + y, 0);
    preview = gelsight_preview(normals_from_height(remove_quadratic(cropped), 1.0f / pad.mm_per_pixel));
    return measure_relief(cropped, pad.mm_per_pixel);
}

/// The capture's centre at the pad's size, as a GelSight image: side by side with the touches
/// at the same scale (pixels of one pitch).
Image capture_preview(const Image& normals, const GelSightPad& pad) {
    const int cx = std::max(0, (normals.width() - pad.width) / 2);
    const int cy = std::max(0, (normals.height() - pad.height) / 2);
    const int cw = std::min(pad.width, normals.width()), ch = std::min(pad.height, normals.height());
    Image centre(cw, ch, 3);
    for (int y = 0; y < ch; ++y)
        for (int x = 0; x < cw; ++x)
            for (int c = 0; c < 3; ++c) centre.at(x, y, c) = normals.at(cx + x, cy + y, c);
    return gelsight_preview(centre);
}

bool within_aim(const TouchRoundTrip& r) {
    return r.tilt_ratio >= kRoundTripMinRatio && r.tilt_ratio <= kRoundTripMaxRatio &&
           r.height_rms_ratio >= kRoundTripMinRatio && r.height_rms_ratio <= kRoundTripMaxRatio;
}

}  // namespace

Json tactile_roundtrip(const std::string& folder, const SceneAssets& assets, const PartsSpec& parts,
                       const ExportScale& scale, std::uint64_t seed) {
    if (!(scale.mm_per_texel > 0) || !(scale.capture_mm_per_pixel > 0) || assets.description.tactile_images.empty())
        return Json();
    const std::unique_ptr<ReliefAsset> asset = load_relief_asset(folder);
    const float uv_mm = scale.mm_per_texel * float(asset->height.height.width());
    std::vector<PartCapture> captures = part_captures(assets, parts, scale, uv_mm);
    int pad_pixels = std::min(scale.capture_width, scale.capture_height);
    draw_touch_points(*asset, captures, pad_pixels, seed);
    const std::string touch_folder = folder + "/touch";
    ensure_folder(touch_folder);
    Json uvs = Json::array(), touch_parts = Json::array(), per_part = Json::array();
    double tilt = 0, rms = 0, spectrum = 0;
    int touched = 0, index = 0;
    for (const PartCapture& part : captures) {
        if (part.points.empty()) continue;
        const GelSightPad pad{pad_pixels, pad_pixels, part.pitch_mm};
        std::vector<ReliefMeasure> measures;
        for (const TouchPoint& p : part.points) {
            Image preview;
            measures.push_back(measure_touch(*asset, p, pad, preview));
            write_png(fmt::format("{}/touch_{:03d}_gelsight.png", touch_folder, index++), preview, 8, Quantize::Round);
            uvs.push_back({p.uv.x, p.uv.y});
            touch_parts.push_back(part.name);
        }
        const CaptureArea area = resolve_capture_area(part.map.normals, CaptureArea::Auto);  // once: the wrap statistics
        const TouchRoundTrip r = compare_touches(measure_capture(part.map.normals, part.pitch_mm, pad.width, area), measures);
        const std::string capture_png = part.name.empty() ? "capture_gelsight.png" : "capture_" + part.name + "_gelsight.png";
        write_png(touch_folder + "/" + capture_png, capture_preview(part.map.normals, pad), 8, Quantize::Round);
        const double n = double(measures.size());
        tilt += r.tilt_ratio * n, rms += r.height_rms_ratio * n, spectrum += r.spectrum_distance * n;
        touched += int(measures.size());
        Json j = r.to_json();
        j["name"] = part.name, j["capture_image"] = part.image, j["capture_preview"] = "touch/" + capture_png;
        j["touch_count"] = int(measures.size()), j["within_aim"] = within_aim(r);
        j["pitch_mm"] = part.pitch_mm;
        j["capture_area"] = area == CaptureArea::Contact ? "contact" : "whole";
        // How much finer (< 1) or coarser the scene lays this part's relief than it was captured.
        if (!part.name.empty()) j["relief_scale"] = part.pitch_mm / part.own_pitch_mm;
        per_part.push_back(j);
    }
    if (touched == 0) {
        log_warning("{}: no point of the asset takes a {} px virtual GelSight pad: no tactile round trip", folder, 32);
        return Json();
    }
    // One part: its comparison as it is; several: the touch-weighted means of the parts'.
    Json j = per_part.size() == 1 ? per_part[0] : Json::object();
    TouchRoundTrip all;
    all.tilt_ratio = tilt / touched, all.height_rms_ratio = rms / touched, all.spectrum_distance = spectrum / touched;
    j["tilt_ratio"] = all.tilt_ratio, j["height_rms_ratio"] = all.height_rms_ratio;
    j["spectrum_distance"] = all.spectrum_distance;
    j["touch_count"] = touched;
    if (captures.size() > 1) j["parts"] = per_part, j["touch_parts"] = touch_parts;
    j.erase("name");
    j["pad"] = {{"width", pad_pixels}, {"height", pad_pixels}, {"mm_per_pixel", captures.front().pitch_mm}};
    j["touch_uvs"] = uvs;
    j["within_aim"] = within_aim(all) && std::all_of(per_part.begin(), per_part.end(), [](const Json& p) {
                          return p["within_aim"].get<bool>();
                      });
    log_info("tactile round trip ({} touches, {} px pad): tilt ratio {:.3f}, height RMS ratio {:.3f}, spectrum "
             "distance {:.3f}",
             touched, pad_pixels, all.tilt_ratio, all.height_rms_ratio, all.spectrum_distance);
    for (const Json& p : per_part)
        if (captures.size() > 1)
            log_info("  part {} ({} touches at {:.4g} mm per pixel, relief laid at {:.3g}x its capture's size): tilt ratio "
                     "{:.3f}, height RMS ratio {:.3f}",
                     p["name"].get<std::string>(), p["touch_count"].get<int>(), p["pitch_mm"].get<double>(),
                     p["relief_scale"].get<double>(), p["tilt_ratio"].get<double>(), p["height_rms_ratio"].get<double>());
    return j;
}

}  // namespace tdf
