#include <fmt/format.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/report/html.h>
#include <tdf/report/run_report.h>

#include <algorithm>
#include <filesystem>
#include <set>

namespace tdf {

namespace fs = std::filesystem;

namespace {

void require_file(const std::string& path, const std::string& what) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw_error("report: {} '{}' does not exist", what, path);
}

std::string image_tag(const std::string& path, const std::string& folder, const std::string& alt,
                      const std::string& css_class = "") {
    require_file(path, "image");
    return fmt::format("<img src=\"{}\" alt=\"{}\"{} loading=\"eager\">",
                       html_escape(relative_url(path, folder)),
                       html_escape(alt),
                       css_class.empty() ? "" : fmt::format(" class=\"{}\"", css_class));
}

// One block per pass with a row per stage, so the same view of input, after-matching and final
// sit above each other.
std::string turntable_section(const RunReport& r, const std::string& folder) {
    if (r.turntables.empty()) return "<p>No turntable renders (export.turntable_views = 0).</p>\n";
    std::string html;
    for (const std::string& pass : r.turntable_passes) {
        std::size_t frames = 0;
        for (const TurntableStage& stage : r.turntables) {
            const auto it = stage.frames.find(pass);
            if (it != stage.frames.end()) frames = std::max(frames, it->second.size());
        }
        if (frames == 0) continue;
        html += fmt::format(
            "<h3>{}</h3>\n<div class=\"turntable\" style=\"--frames:{}\">\n", html_escape(pass), frames);
        for (const TurntableStage& stage : r.turntables) {
            html += fmt::format("<div class=\"label\">{}<div class=\"meaning\">{}</div></div>",
                                html_escape(stage.label),
                                html_escape(stage.description));
            const auto it = stage.frames.find(pass);
            for (std::size_t k = 0; k < frames; ++k) {
                if (it != stage.frames.end() && k < it->second.size())
                    html +=
                        image_tag(it->second[k], folder, fmt::format("{} {} view {}", stage.label, pass, k));
                else
                    html += "<div></div>";
            }
            html += "\n";
        }
        html += "</div>\n";
    }
    return html;
}

std::string quality_section(const RunReport& r) {
    if (r.quality.empty()) return "<p>No quality report.</p>\n";
    std::vector<std::string> keys;
    std::set<std::string> seen;
    for (const auto& [label, values] : r.quality)
        for (auto it = values.begin(); it != values.end(); ++it)
            if (seen.insert(it.key()).second) keys.push_back(it.key());
    std::string html = "<table>\n<tr><th>measure</th>";
    for (const auto& column : r.quality)
        html += fmt::format("<th class=\"num\">{}</th>", html_escape(column.first));
    html += "<th>meaning</th></tr>\n";
    for (const std::string& key : keys) {
        html += fmt::format("<tr><td><code>{}</code></td>", html_escape(key));
        for (const auto& column : r.quality) {
            const auto it = column.second.find(key);
            html += fmt::format("<td class=\"num\">{}</td>",
                                html_escape(it == column.second.end() ? "-" : format_json_value(*it)));
        }
        html += fmt::format("<td class=\"meaning\">{}</td></tr>\n", html_escape(quality_meaning(key)));
    }
    return html + "</table>\n";
}

// Issue 29: the albedo against the input at its darkest and brightest spot, and the three
// numbers that say whether refinement painted light into it, each beside its aim.
std::string colour_section(const RunReport& r, const std::string& folder) {
    if (r.colour.empty() && r.albedo_spots.empty()) return "";
    std::string html = "<h2 id=\"colour\">Albedo against the input</h2>\n";
    if (!r.colour.empty()) {
        const Json aims = r.colour.value("aims", Json::object());
        const Json met = r.colour.value("met", Json::object());
        html += "<table>\n<tr><th>measure</th><th class=\"num\">final</th><th class=\"num\">aim</th>"
                "<th>met</th><th>meaning</th></tr>\n";
        for (const char* key : {"albedo_psnr_lowpass_db", "colour_geometry_correlation", "added_colour_geometry_correlation",
                                "max_above_local_max"}) {
            const auto it = r.colour.find(key);
            const auto verdict = met.find(key);
            html += fmt::format("<tr><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
                                "<td>{}</td><td class=\"meaning\">{}</td></tr>\n",
                                key, html_escape(it == r.colour.end() ? "-" : format_json_value(*it)),
                                html_escape(aims.value(key, "")),
                                verdict == met.end() ? "" : verdict->get<bool>() ? "yes" : "<b>no</b>",
                                html_escape(quality_meaning(key)));
        }
        html += "</table>\n";
    }
    html += "<div class=\"figures\">\n";
    for (const ReportImage& spot : r.albedo_spots)
        html += fmt::format("<figure>{}<figcaption>{}</figcaption></figure>\n",
                            image_tag(spot.path, folder, spot.caption, "strip"), html_escape(spot.caption));
    return html + "</div>\n";
}

// Issue 24: the relief's scale, and what a virtual GelSight pressed on the asset measures
// against the input capture, with the capture and the touches side by side.
std::string touch_section(const RunReport& r, const std::string& folder) {
    if (r.height_map.empty() && r.tactile_roundtrip.empty()) return "";
    std::string html = "<h2 id=\"touch\">Relief and touch</h2>\n<table>\n<tr><th>measure</th><th class=\"num\">value</th></tr>\n";
    const auto row = [&](const Json& j, const char* key) {
        const auto it = j.find(key);
        if (it != j.end())
            html += fmt::format("<tr><td><code>{}</code></td><td class=\"num\">{}</td></tr>\n", key,
                                html_escape(format_json_value(*it)));
    };
    for (const char* key : {"mm_per_texel", "mm_per_unit", "min_mm", "max_mm", "mm_per_step", "normal_consistency_cosine",
                            "mm_per_texel_assumed"})
        row(r.height_map, key);
    for (const char* key : {"texel_size", "seam_links", "texture_space_cosine", "surface_cosine"}) row(r.height_map, key);
    for (const char* key : {"tilt_ratio", "height_rms_ratio", "spectrum_distance", "touch_count", "within_aim"})
        row(r.tactile_roundtrip, key);
    for (const Json& part : r.tactile_roundtrip.value("parts", Json::array()))
        html += fmt::format("<tr><td>part <code>{}</code>: tilt / height RMS ratio ({} touches)</td><td "
                            "class=\"num\">{:.3f} / {:.3f}</td></tr>\n",
                            html_escape(part.value("name", "")), part.value("touch_count", 0),
                            part.value("tilt_ratio", 0.0), part.value("height_rms_ratio", 0.0));
    html += "</table>\n<p>Tilt and height RMS ratios: the virtual GelSight's touches over the input capture's "
            "contact region (aim [0.85, 1.15]); spectrum distance: half the L1 distance of their detail "
            "energy per octave (0 = the same).</p>\n<div class=\"figures\">\n";
    for (const ReportImage& t : r.touches)
        html += fmt::format("<figure>{}<figcaption>{}</figcaption></figure>\n", image_tag(t.path, folder, t.caption),
                            html_escape(t.caption));
    return html + "</div>\n";
}

// Multi-part runs: each part's mask, the relief it should carry and its numbers.
std::string parts_section(const RunReport& r, const std::string& folder) {
    if (!r.parts.is_array() || r.parts.empty()) return "";
    std::string html = "<h2 id=\"parts\">Parts</h2>\n<table>\n<tr><th>part</th><th>mask</th><th>material</th>";
    const char* keys[] = {"label_accuracy", "bleed_texels", "tilt_ratio", "normal_cosine"};
    for (const char* key : keys) html += fmt::format("<th class=\"num\"><code>{}</code></th>", key);
    html += "</tr>\n";
    for (const Json& part : r.parts) {
        const std::string name = part.value("name", "");
        html += fmt::format("<tr><td><span style=\"display:inline-block;width:1em;height:1em;background:{}\"></span> {}</td>",
                            html_escape(part.value("colour", "#000000")), html_escape(name));
        for (const char* image : {"mask", "swatch"}) {
            const std::string file = part.value(image, "");
            html += "<td>" + (file.empty() ? std::string("-") : image_tag(folder + "/" + file, folder, name + " " + image, "thumb")) +
                    "</td>";
        }
        for (const char* key : keys) {
            const auto it = part.find(key);
            html += fmt::format("<td class=\"num\">{}</td>", html_escape(it == part.end() ? "-" : format_json_value(*it)));
        }
        html += "</tr>\n";
    }
    html += "</table>\n<p class=\"meaning\">";
    for (const char* key : keys) html += fmt::format("<code>{}</code>: {} ", key, html_escape(quality_meaning(key)));
    return html + "</p>\n";
}

// First, end-of-matching and last value of every loss term: the numbers behind the plot.
std::string loss_table(const RunReport& r) {
    if (!r.losses.is_array() || r.losses.empty()) return "";
    const Json& first = r.losses.front();
    const Json& last = r.losses.back();
    const Json* matched = nullptr;
    for (const Json& record : r.losses)
        if (record.value("iteration", -1) == r.init_iterations - 1 ||
            record.value("iteration", -1) == r.init_iterations)
            matched = &record;
    std::vector<std::string> terms;
    std::set<std::string> seen;
    for (const Json& record : r.losses)
        for (auto it = record.begin(); it != record.end(); ++it)
            if (it.key() != "iteration" && it.key() != "seconds" && seen.insert(it.key()).second)
                terms.push_back(it.key());
    const auto cell = [](const Json* record, const std::string& key) {
        if (!record) return std::string("-");
        const auto it = record->find(key);
        return it == record->end() ? std::string("-") : format_json_value(*it);
    };
    std::string html = fmt::format(
        "<table>\n<tr><th>term (weighted)</th><th class=\"num\">iteration {}</th><th class=\"num\">iteration "
        "{} "
        "(end of matching)</th><th class=\"num\">iteration {} (last)</th></tr>\n",
        first.value("iteration", 0),
        matched ? matched->value("iteration", 0) : r.init_iterations,
        last.value("iteration", 0));
    for (const std::string& term : terms)
        html += fmt::format(
            "<tr><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
            "<td class=\"num\">{}</td></tr>\n",
            html_escape(term),
            html_escape(cell(&first, term)),
            html_escape(cell(matched, term)),
            html_escape(cell(&last, term)));
    return html + "</table>\n";
}

std::string inline_svg(const std::string& path) {
    require_file(path, "loss plot");
    std::string svg = read_text_file(path);
    // An XML declaration is not allowed inside HTML.
    if (svg.rfind("<?xml", 0) == 0) {
        const auto end = svg.find("?>");
        if (end != std::string::npos) svg = svg.substr(end + 2);
    }
    return "<div class=\"loss-plot\">" + svg + "</div>\n";
}

std::string timings_section(const Json& timings) {
    if (!timings.is_object() || timings.empty()) return "<p>No timings.</p>\n";
    std::string html = "<table>\n";
    for (auto it = timings.begin(); it != timings.end(); ++it) {
        if (it->is_object()) {
            html += fmt::format("<tr><th colspan=\"2\">{}</th></tr>\n", html_escape(it.key()));
            for (auto sub = it->begin(); sub != it->end(); ++sub)
                html += fmt::format("<tr><td>&nbsp;&nbsp;{}</td><td class=\"num\">{}</td></tr>\n",
                                    html_escape(sub.key()),
                                    html_escape(format_json_value(*sub)));
        } else {
            html += fmt::format("<tr><td>{}</td><td class=\"num\">{}</td></tr>\n",
                                html_escape(it.key()),
                                html_escape(format_json_value(*it)));
        }
    }
    return html + "</table>\n";
}

}  // namespace

std::string quality_meaning(const std::string& key) {
    static const std::map<std::string, std::string> kMeanings = {
        {"albedo_psnr_foreground_db",
         "PSNR (dB) of the learned albedo against the input's colour over the covered pixels of held-out "
         "views "
         "(never trained on); higher is closer, 30 dB and above is hard to tell apart."},
        {"albedo_psnr_full_image_db",
         "the same PSNR over whole images, white background included (higher is better)."},
        {"albedo_max_error",
         "largest per-channel albedo error on covered pixels of the held-out views, in [0, 1]."},
        {"tactile_mean_cosine",
         "mean cosine between learned and target view-space normals in held-out tactile patches: 1 = the "
         "texture's "
         "relief is reproduced exactly, 0 = unrelated."},
        {"colour_geometry_correlation",
         "how much the albedo follows the relief (correlation of colour and shading detail over held-out "
         "views): what "
         "visual guidance raises; near 0 means colour and bumps ignore each other."},
        {"tactile_tilt_distance",
         "L1 distance between the tilt histograms of the learned normals and of the tactile map: 0 = the "
         "relief has "
         "the texture's statistics wherever it lies (lower is better)."},
        {"added_colour_geometry_correlation",
         "the same correlation on what the run added (learned minus input albedo): whether the colour the "
         "refinement put in follows the relief, whatever prints the input carries (0 = nothing added)."},
        {"target_tilt_distance",
         "the same distance for the training target itself: the floor tactile_tilt_distance can reach."},
        {"albedo_psnr_lowpass_db",
         "PSNR (dB) of the exported albedo against the input's, texel by texel after a 2-texel Gaussian on "
         "both: refinement may add fine relief-aligned colour, but the colour at a glance must stay the input's."},
        {"max_above_local_max",
         "how far the brightest channel of any texel rises above the brightest the input had within 4 texels "
         "of it (same chart): light painted into the albedo shows here; 0 = nothing brighter than its "
         "neighbourhood."},
        {"held_out_views", "number of held-out visual views the numbers are measured on."},
        {"held_out_patches", "number of held-out tactile patches the numbers are measured on."},
        {"label_accuracy", "share of the part's texels the label head predicts as the part (the label map)."},
        {"bleed_texels",
         "after matching: farthest texel of the part (texels from another part) whose normal differs from the "
         "part's own map by more than 1 degree; aim <= 2."},
        {"tilt_ratio",
         "final normal map's mean detail tilt over the part's texels / its own map's laid there: 1 = its own "
         "relief's strength; aim 0.85-1.15."},
        {"normal_cosine", "mean cosine of the final normal map against the part's own laid map over its texels."},
    };
    const auto it = kMeanings.find(key);
    return it == kMeanings.end() ? std::string() : it->second;
}

void write_run_report(const std::string& html_path, const RunReport& r) {
    const std::string folder = fs::path(html_path).parent_path().string();
    const bool three = install_report_assets(folder);
    std::string body = html_page_begin(fmt::format("{} - tdf optimize report", r.name));
    body += fmt::format(
        "<h1>{}</h1>\n<p class=\"subtitle\">tdf optimize report &middot; scene <code>{}</code></p>\n",
        html_escape(r.name),
        html_escape(r.scene_path));
    body +=
        "<nav class=\"card\"><a href=\"#turntables\">turntables</a> &middot; <a href=\"#viewer\">3D view</a> "
        "&middot; <a href=\"#quality\">quality</a> &middot; <a href=\"#colour\">albedo vs input</a> &middot; " +
        std::string(r.parts.empty() ? "" : "<a href=\"#parts\">parts</a> &middot; ") + "<a href=\"#touch\">relief and touch</a> &middot; <a href=\"#maps\">maps</a> &middot; <a "
        "href=\"#losses\">losses</a> &middot; <a href=\"#timings\">timings</a> &middot; <a "
        "href=\"#config\">configuration</a></nav>\n";

    body += "<h2 id=\"turntables\">Input, after matching, final</h2>\n";
    body += turntable_section(r, folder);

    std::vector<std::string> model_scripts;
    body += "<h2 id=\"viewer\">3D view of the exported asset</h2>\n";
    if (r.glb_path.empty()) {
        body += "<p>No .glb was exported (export.glb = false).</p>\n";
    } else {
        require_file(r.glb_path, "model");
        const std::string stem = fs::path(html_path).stem().string();
        body += viewer_html(folder, r.glb_path, stem, r.camera);
        model_scripts.push_back(relative_url((fs::path(folder) / (stem + "_model.js")).string(), folder));
    }

    body += "<h2 id=\"quality\">Quality (held-out views and patches)</h2>\n" + quality_section(r);

    body += colour_section(r, folder);
    body += parts_section(r, folder);
    body += touch_section(r, folder);

    body += "<h2 id=\"maps\">Exported maps</h2>\n<div class=\"figures\">\n";
    for (const ReportImage& m : r.maps)
        body += fmt::format("<figure><a href=\"{}\">{}</a><figcaption>{}</figcaption></figure>\n",
                            html_escape(relative_url(m.path, folder)),
                            image_tag(m.path, folder, m.caption),
                            html_escape(m.caption));
    body += "</div>\n";

    body += "<h2 id=\"losses\">Loss curves</h2>\n";
    if (r.losses.is_array() && !r.losses.empty()) {
        body += fmt::format(
            "<script type=\"application/json\" id=\"losses-data\">{}</script>\n"
            "<div class=\"tdf-plot\" data-source=\"losses-data\" data-boundary=\"{}\">"
            "<canvas width=\"900\" height=\"360\"></canvas><div class=\"tdf-plot-legend\"></div>"
            "<div class=\"tdf-plot-readout\"></div></div>\n",
            json_for_html(r.losses),
            r.init_iterations);
        if (!r.loss_plot_svg.empty()) body += "<noscript>" + inline_svg(r.loss_plot_svg) + "</noscript>\n";
    } else if (!r.loss_plot_svg.empty()) {
        body += inline_svg(r.loss_plot_svg);
    }
    if (!r.loss_plot_svg.empty())
        body += fmt::format(
            "<p class=\"meaning\">weighted terms, log scale; the same plot as a file: <a href=\"{}\">{}</a>"
            "</p>\n",
            html_escape(relative_url(r.loss_plot_svg, folder)),
            html_escape(fs::path(r.loss_plot_svg).filename().string()));
    body += loss_table(r);

    body += "<h2 id=\"timings\">Timings</h2>\n" + timings_section(r.timings);

    body += "<h2 id=\"config\">Resolved configuration</h2>\n<details><summary>show (" +
            std::to_string(r.config.size()) + " keys)</summary>\n<pre>" + html_escape(r.config.dump(2)) +
            "</pre></details>\n";
    if (!r.links.empty()) {
        body += "<h2>Files</h2>\n<ul>\n";
        for (const ReportImage& l : r.links)
            body += fmt::format("<li><a href=\"{}\">{}</a> {}</li>\n",
                                html_escape(relative_url(l.path, folder)),
                                html_escape(fs::path(l.path).filename().string()),
                                html_escape(l.caption));
        body += "</ul>\n";
    }
    body += html_page_end(viewer_scripts_html(model_scripts, three && !model_scripts.empty()) +
                          "<script src=\"" + std::string(kReportAssetsFolder) +
                          "/tdf_plot.js\"></script>\n"
                          "<script>window.tdfStartPlots();</script>\n");
    write_text_atomically(html_path, body);
}

}  // namespace tdf
