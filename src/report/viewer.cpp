#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/report/html.h>
#include <tdf/report/viewer.h>

#include <filesystem>

namespace tdf {

namespace fs = std::filesystem;

namespace {
// Dark grey: the light and dark parts of a model both stand out; the page's colour input changes it.
constexpr const char* kBackground = "#30343a";
}  // namespace

ViewerCamera ViewerCamera::from_orbit(float elevation_deg, float azimuth_deg, float radius_, float fovy_deg,
                                      Vec3f target_, int width_, int height_) {
    const Camera camera =
        Camera::orbit(elevation_deg, azimuth_deg, radius_, fovy_deg, width_, height_, target_);
    ViewerCamera v;
    v.position = camera.position;
    v.target = target_;
    v.fovy_degrees = fovy_deg;
    v.near_plane = 0.01f * radius_;
    v.far_plane = 100.0f * radius_;
    v.width = width_;
    v.height = height_;
    v.elevation_degrees = elevation_deg;
    v.azimuth_degrees = azimuth_deg;
    v.radius = radius_;
    return v;
}

std::string viewer_html(const std::string& page_folder, const std::string& glb_path, const std::string& stem,
                        const ViewerCamera& camera) {
    const std::string model_id = stem + "_model";
    const std::string script_path =
        (fs::path(page_folder.empty() ? "." : page_folder) / (model_id + ".js")).string();
    const std::string glb = read_text_file(glb_path);
    write_text_atomically(script_path,
                          fmt::format("window.tdfModels = window.tdfModels || {{}};\n"
                                      "window.tdfModels[{}] = \"{}\";\n",
                                      Json(model_id).dump(),
                                      base64_encode(glb)));
    const Json spec = {{"position", {camera.position.x, camera.position.y, camera.position.z}},
                       {"target", {camera.target.x, camera.target.y, camera.target.z}},
                       {"fovy", camera.fovy_degrees},
                       {"near", camera.near_plane},
                       {"far", camera.far_plane},
                       {"orbit",
                        {{"elevation", camera.elevation_degrees},
                         {"azimuth", camera.azimuth_degrees},
                         {"radius", camera.radius}}},
                       {"background", kBackground}};
    return fmt::format(
        "<div class=\"tdf-viewer\" data-model=\"{id}\" data-state=\"loading\" data-camera=\"{camera}\">\n"
        "<canvas width=\"{w}\" height=\"{h}\" style=\"width:{w}px;height:{h}px\"></canvas>\n"
        "<div class=\"controls\">\n"
        "<label for=\"{id}-az\">light azimuth</label><input id=\"{id}-az\" type=\"range\" min=\"-180\" "
        "max=\"180\" "
        "value=\"35\" data-control=\"light-azimuth\">\n"
        "<label for=\"{id}-el\">light elevation</label><input id=\"{id}-el\" type=\"range\" min=\"-89\" "
        "max=\"89\" "
        "value=\"25\" data-control=\"light-elevation\">\n"
        "<label for=\"{id}-nm\">normal map</label><span><input id=\"{id}-nm\" type=\"checkbox\" checked "
        "data-control=\"normal-map\"></span>\n"
        "<label for=\"{id}-bg\">background</label><span><input id=\"{id}-bg\" type=\"color\" value=\"{bg}\" "
        "data-control=\"background\"></span>\n"
        "<span></span><span><button type=\"button\" data-control=\"reset\">reset view</button></span>\n"
        "<div class=\"tdf-viewer-status\">the 3D view needs JavaScript</div>\n"
        "<div class=\"tdf-viewer-status-file\"><a href=\"{glb}\">{glb_name}</a> (glTF 2.0 binary)</div>\n"
        "</div>\n</div>\n",
        fmt::arg("id", html_escape(model_id)),
        fmt::arg("camera", html_escape(spec.dump())),
        fmt::arg("bg", kBackground), fmt::arg("w", camera.width),
        fmt::arg("h", camera.height),
        fmt::arg("glb", html_escape(relative_url(glb_path, page_folder))),
        fmt::arg("glb_name", html_escape(fs::path(glb_path).filename().string())));
}

std::string viewer_scripts_html(const std::vector<std::string>& model_scripts, bool three_installed) {
    std::string html;
    for (const std::string& s : model_scripts)
        html += fmt::format("<script src=\"{}\"></script>\n", html_escape(s));
    const std::string a = kReportAssetsFolder;
    // Without three.js the tags are left out (a missing script is a console error); the viewer
    // then says in the page why there is no 3D view.
    if (three_installed)
        html += fmt::format(
            "<script src=\"{0}/three.min.js\"></script>\n"
            "<script src=\"{0}/GLTFLoader.js\"></script>\n"
            "<script src=\"{0}/OrbitControls.js\"></script>\n",
            a);
    html += fmt::format(
        "<script src=\"{}/tdf_viewer.js\"></script>\n<script>window.tdfStartViewers();</script>\n", a);
    return html;
}

}  // namespace tdf
