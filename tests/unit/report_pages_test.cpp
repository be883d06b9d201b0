// The three page writers with hand-made inputs: what they link, what they refuse, the order of
// rows. (The pages are opened in a real browser by the `browser` ctest label, report_browser.cmake.)
#include <gtest/gtest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/mesh/mesh_writer.h>
#include <tdf/report/batch_index.h>
#include <tdf/report/compare_report.h>
#include <tdf/report/html.h>
#include <tdf/report/run_report.h>
#include <tdf/scene/procedural_mesh.h>

#include <filesystem>

#include "common/test_paths.h"

namespace tdf {
namespace {

namespace fs = std::filesystem;

std::string fresh_folder(const std::string& name) {
    const std::string folder = test::scratch_dir() + "/report_pages/" + name;
    fs::remove_all(folder);
    ensure_folder(folder);
    return folder;
}

Image gradient(int size, float shift) {
    Image image(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            image.at(x, y, 0) = float(x) / float(size - 1);
            image.at(x, y, 1) = float(y) / float(size - 1);
            image.at(x, y, 2) = shift;
        }
    return image;
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
    return n;
}

TEST(ReportBatchIndex, ListsEveryJobWithRelativeLinksAndQualityColumns) {
    const std::string folder = fresh_folder("batch");
    write_png(folder + "/jobs/a/thumb.png", gradient(8, 0.2f));
    write_text_atomically(folder + "/jobs/a/a_report.html", html_page_begin("a") + html_page_end());
    std::vector<BatchRow> rows = {{"a",
                                   "ok",
                                   "",
                                   12.5,
                                   {{"albedo_psnr_foreground_db", 31.2}},
                                   folder + "/jobs/a/a_report.html",
                                   folder + "/jobs/a/thumb.png"},
                                  {"b <odd>",
                                   "failed",
                                   "b/scene.json: mesh 'x.obj' does not exist",
                                   0.4,
                                   {},
                                   folder + "/jobs/b/none.html",
                                   ""},
                                  {"c", "ok", "", -1, {{"tactile_mean_cosine", 0.8}}, "", ""}};
    write_batch_index(folder + "/index.html", "batch", rows);
    const std::string html = read_text_file(folder + "/index.html");
    EXPECT_NE(html.find("href=\"jobs/a/a_report.html\""), std::string::npos);
    EXPECT_NE(html.find("src=\"jobs/a/thumb.png\""), std::string::npos);
    EXPECT_NE(html.find("b &lt;odd&gt;"), std::string::npos) << "job names are escaped";
    EXPECT_EQ(html.find("jobs/b/none.html"), std::string::npos) << "a missing job page is not linked";
    EXPECT_NE(html.find("mesh &#39;x.obj&#39; does not exist"), std::string::npos);
    EXPECT_NE(html.find(">albedo_psnr_foreground_db</th>"), std::string::npos);
    EXPECT_NE(html.find(">tactile_mean_cosine</th>"), std::string::npos);
    EXPECT_EQ(count(html, "<tr>"), 4u) << "header + 3 rows";
    EXPECT_NE(html.find("1 failed"), std::string::npos);
    EXPECT_NE(html.find("data-value=\"12.5\""), std::string::npos);

    rows[0].thumbnail = folder + "/missing.png";
    EXPECT_THROW(write_batch_index(folder + "/index2.html", "batch", rows), Error);
    EXPECT_FALSE(fs::exists(folder + "/index2.html"));
}

std::vector<ExrLayer> render_like(float albedo_shift) {
    Image mask(16, 16, 1, 1.0f);
    return {{"albedo", {"R", "G", "B"}, gradient(16, albedo_shift)}, {"mask", {"Y"}, mask}};
}

TEST(ReportCompare, WritesPreviewsAndHeatmapsAndPutsFailuresFirst) {
    const std::string folder = fresh_folder("compare");
    CompareOptions options;
    options.fail = 0.01f;
    const auto a = render_like(0.5f);
    const auto same = render_like(0.5f);
    const auto other = render_like(0.6f);
    CompareReport report;
    report.thresholds = options;
    const std::string images = report_files_folder(folder + "/page.html");
    EXPECT_EQ(images, folder + "/page_files");
    report.files.push_back(compare_file_entry("equal.exr",
                                              "a/equal.exr",
                                              "b/equal.exr",
                                              a,
                                              same,
                                              compare_layers(a, same, options),
                                              options,
                                              images,
                                              "f0"));
    report.files.push_back(compare_file_entry("differs.exr",
                                              "a/differs.exr",
                                              "b/differs.exr",
                                              a,
                                              other,
                                              compare_layers(a, other, options),
                                              options,
                                              images,
                                              "f1"));
    ASSERT_EQ(report.files[1].passes.size(), 2u);
    EXPECT_EQ(report.files[1].result, "fail");
    EXPECT_EQ(report.files[1].passes[0].name, "albedo") << "failing pass first";
    EXPECT_FALSE(report.files[1].passes[0].passed);
    EXPECT_TRUE(report.files[1].passes[1].passed);
    EXPECT_NEAR(report.files[1].passes[0].heat_scale, 0.1, 1e-5);
    EXPECT_EQ(report.files[0].passes[0].heat_scale, 0.0);
    const Image heat = read_image(report.files[1].passes[0].heatmap);
    EXPECT_GT(heat.at(3, 3, 0), 0.9f) << "uniform largest difference maps to the top of the ramp";

    report.files.push_back(compare_file_problem(
        "missing.exr", "a/missing.exr", "b/missing.exr", "missing_b", "B has no missing.exr"));
    write_compare_report(folder + "/page.html", report);
    const std::string html = read_text_file(folder + "/page.html");
    ASSERT_NE(html.find("differs.exr"), std::string::npos);
    EXPECT_LT(html.find("differs.exr"), html.find("equal.exr")) << "failures first";
    EXPECT_NE(html.find("src=\"page_files/f1_albedo_diff.png\""), std::string::npos);
    EXPECT_NE(html.find("2 failed"), std::string::npos);
    ASSERT_NE(html.find("B has no missing.exr"), std::string::npos);
    EXPECT_LT(html.find("missing.exr"), html.find("equal.exr")) << "problems are failures too";
}

TEST(ReportRun, ShowsTheAlbedoAgainstTheInputWithItsAims) {
    // Issue 29: the three numbers beside their aims, whether each is met, and the spot strips.
    const std::string folder = fresh_folder("colour");
    write_png(folder + "/ball_albedo_spot_dark.png", gradient(8, 0.1f));
    RunReport r;
    r.name = "ball";
    r.colour = {{"albedo_psnr_lowpass_db", 38.25},
                {"added_colour_geometry_correlation", 0.31},
                {"max_above_local_max", 0.04},
                {"aims", {{"albedo_psnr_lowpass_db", ">= 33"}, {"added_colour_geometry_correlation", ">= 0.4"}}},
                {"met", {{"albedo_psnr_lowpass_db", true}, {"added_colour_geometry_correlation", false}}}};
    r.albedo_spots.push_back({"dark spot: input | after matching | final", folder + "/ball_albedo_spot_dark.png"});
    write_run_report(folder + "/ball_report.html", r);
    const std::string html = read_text_file(folder + "/ball_report.html");
    const auto row = [&](const std::string& key) {
        const auto at = html.find("<code>" + key + "</code></td><td class=\"num\">", html.find("id=\"colour\""));
        return at == std::string::npos ? std::string() : html.substr(at, html.find("</tr>", at) - at);
    };
    EXPECT_NE(row("albedo_psnr_lowpass_db").find(">38.25<"), std::string::npos);
    EXPECT_NE(row("albedo_psnr_lowpass_db").find("&gt;= 33</td><td>yes<"), std::string::npos);
    EXPECT_NE(row("added_colour_geometry_correlation").find("<b>no</b>"), std::string::npos);
    EXPECT_NE(html.find("src=\"ball_albedo_spot_dark.png\""), std::string::npos);
    EXPECT_NE(html.find("class=\"strip\""), std::string::npos) << "strips are shown at their own size";
}

TEST(ReportRun, EmbedsTheModelAndLinksEveryImage) {
    const std::string folder = fresh_folder("run");
    const TriangleMesh mesh = make_uv_sphere(1.0f, 16, 8);
    write_glb(folder + "/ball.glb", mesh);
    write_png(folder + "/turntable/albedo_000.png", gradient(8, 0.1f));
    write_png(folder + "/ball_albedo.png", gradient(8, 0.3f));
    write_text_atomically(folder + "/ball_loss_plot.svg",
                          "<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10\" "
                          "height=\"10\"></svg>\n");
    RunReport r;
    r.name = "ball";
    r.turntables.push_back({"final", "", {{"albedo", {folder + "/turntable/albedo_000.png"}}}});
    r.maps.push_back({"albedo", folder + "/ball_albedo.png"});
    r.loss_plot_svg = folder + "/ball_loss_plot.svg";
    r.losses = Json::array({Json{{"iteration", 0}, {"total", 2.0}}, Json{{"iteration", 1}, {"total", 1.0}}});
    r.init_iterations = 1;
    r.quality = {{"final", Json{{"albedo_psnr_foreground_db", 30.5}, {"something_new", 1}}}};
    r.glb_path = folder + "/ball.glb";
    write_run_report(folder + "/ball_report.html", r);

    const std::string html = read_text_file(folder + "/ball_report.html");
    EXPECT_NE(html.find("src=\"turntable/albedo_000.png\""), std::string::npos);
    EXPECT_NE(html.find("<svg"), std::string::npos);
    EXPECT_EQ(html.find("<?xml"), std::string::npos) << "the SVG is inlined without its XML declaration";
    EXPECT_NE(html.find(html_escape(quality_meaning("albedo_psnr_foreground_db"))), std::string::npos);
    EXPECT_NE(html.find("something_new"), std::string::npos);
    EXPECT_NE(html.find("src=\"ball_report_model.js\""), std::string::npos);
    const std::string model = read_text_file(folder + "/ball_report_model.js");
    EXPECT_NE(model.find(base64_encode(read_text_file(folder + "/ball.glb"))), std::string::npos);
    EXPECT_TRUE(fs::exists(folder + "/report_assets/tdf_viewer.js"));
    if (fs::exists(web_modules_folder() + "/three/build/three.min.js")) {
        EXPECT_TRUE(fs::exists(folder + "/report_assets/three.min.js"));
        EXPECT_NE(html.find("report_assets/GLTFLoader.js"), std::string::npos);
    } else {
        EXPECT_EQ(html.find("three.min.js"), std::string::npos) << "no tag for a script that is not there";
    }

    r.maps.push_back({"gone", folder + "/gone.png"});
    EXPECT_THROW(write_run_report(folder + "/ball_report2.html", r), Error);
}

}  // namespace
}  // namespace tdf
