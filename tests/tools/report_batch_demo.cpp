// Writes a batch index page with hand-made rows (issue 16), for the browser test: until `tdf
// batch` writes its own index, this exercises write_batch_index with every kind of row.
//   report_batch_demo OUT_DIR [JOB_PAGE [THUMBNAIL]]
// OUT_DIR/index.html links JOB_PAGE (e.g. the browser test's run page) and shows THUMBNAIL.
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>
#include <tdf/report/batch_index.h>
#include <tdf/report/html.h>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: report_batch_demo OUT_DIR [JOB_PAGE [THUMBNAIL]]\n");
        return 2;
    }
    try {
        const std::string out = argv[1];
        tdf::ensure_folder(out + "/jobs");
        // Two more jobs with their own small pages and thumbnails.
        for (int j = 0; j < 2; ++j) {
            tdf::Image thumb(32, 32, 3);
            for (int y = 0; y < 32; ++y)
                for (int x = 0; x < 32; ++x) {
                    thumb.at(x, y, 0) = float(x) / 31.f;
                    thumb.at(x, y, 1) = float(y) / 31.f;
                    thumb.at(x, y, 2) = float(j);
                }
            const std::string job = "job" + std::to_string(j);
            tdf::write_png(out + "/jobs/" + job + "/thumb.png", thumb);
            tdf::write_text_atomically(
                out + "/jobs/" + job + "/" + job + "_report.html",
                tdf::html_page_begin(job) + "<h1>" + job + "</h1>\n" + tdf::html_page_end());
        }
        std::vector<tdf::BatchRow> rows = {
            {"job0",
             "ok",
             "",
             41.5,
             {{"albedo_psnr_foreground_db", 27.3}, {"tactile_mean_cosine", 0.91}},
             out + "/jobs/job0/job0_report.html",
             out + "/jobs/job0/thumb.png"},
            {"broken_scene",
             "failed",
             "scenes/broken/scene.json: mesh '../missing.obj' does not exist",
             0.2,
             {},
             "",
             ""},
            {"job1",
             "ok",
             "",
             7.25,
             {{"albedo_psnr_foreground_db", 31.9}, {"tactile_mean_cosine", 0.84}},
             out + "/jobs/job1/job1_report.html",
             out + "/jobs/job1/thumb.png"},
            {"slow_one",
             "timeout",
             "stopped after 3600 s (batch time limit)",
             3600,
             {{"tactile_mean_cosine", 0.5}},
             "",
             ""}};
        if (argc >= 3)
            rows.push_back({"pebble_sphere",
                            "ok",
                            "",
                            12.0,
                            {{"albedo_psnr_foreground_db", 24.4}},
                            argv[2],
                            argc >= 4 ? argv[3] : ""});
        tdf::write_batch_index(out + "/index.html", "batch: hand-made rows", rows);
        std::printf("wrote %s/index.html\n", out.c_str());
        return 0;
    } catch (const tdf::Error& e) {
        std::fprintf(stderr, "report_batch_demo: %s\n", e.what());
        return 1;
    }
}
