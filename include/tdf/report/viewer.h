#pragma once
/// The interactive 3D view of an exported .glb in a report page (three.js r147, classic scripts).
/// The model travels as base64 inside a script file beside the page (`<stem>_model.js`), because a
/// page opened from file:// may not fetch() a file beside it in Chromium.
#include <tdf/core/vec.h>
#include <tdf/scene/camera.h>

#include <string>
#include <vector>

namespace tdf {

/// The viewer's start camera, in the mesh's (= the glTF's) coordinates: world Y up, looking from
/// `position` at `target`, vertical field of view `fovy_degrees`. Built from a tdf Camera it
/// shows the same picture as tdf's renderer (same look-at convention), which the browser test
/// checks against the renderer's silhouette.
struct ViewerCamera {
    Vec3f position{0, 0, 3};
    Vec3f target{0, 0, 0};
    float fovy_degrees = 50.0f;
    float near_plane = 0.01f;
    float far_plane = 100.0f;
    int width = 512;  ///< canvas size in CSS pixels
    int height = 512;
    /// For `tdf render` of the same view (tests): the orbit parameters this camera came from.
    float elevation_degrees = 0, azimuth_degrees = 0, radius = 3;

    static ViewerCamera from_orbit(float elevation_deg, float azimuth_deg, float radius, float fovy_deg,
                                   Vec3f target, int width, int height);
};

/// Writes `<page_folder>/<stem>_model.js` (the .glb as base64) and returns the viewer's HTML: the
/// canvas, the light and normal-map controls, and a data-camera attribute. The page must load
/// the scripts of viewer_scripts_html() after it. Throws tdf::Error when the .glb cannot be read.
std::string viewer_html(const std::string& page_folder, const std::string& glb_path, const std::string& stem,
                        const ViewerCamera& camera);

/// The `<script>` tags that run every viewer on a page, with `model_scripts` (the `<stem>_model.js`
/// files, relative URLs) loaded first. `three_installed` is what install_report_assets() returned.
std::string viewer_scripts_html(const std::vector<std::string>& model_scripts, bool three_installed);

}  // namespace tdf
