#pragma once
/// The index page of a batch of runs: one row per job with its thumbnail, status, error line,
/// wall time and quality numbers, linking to the job's own page. Columns sort on a click (the
/// page's inline script; numbers sort numerically, missing values last).
#include <tdf/core/config.h>

#include <string>
#include <utility>
#include <vector>

namespace tdf {

struct BatchRow {
    std::string job;           ///< the job's name
    std::string status;        ///< "ok", "failed", "skipped", ... (failed/error rows are shown red)
    std::string error;         ///< the error line of a failed job; empty otherwise
    double wall_seconds = -1;  ///< wall time, seconds; negative: unknown
    /// Quality numbers by name (e.g. albedo_psnr_foreground_db), one column per distinct name
    /// over all rows, in first-seen order.
    std::vector<std::pair<std::string, double>> quality;
    std::string page;       ///< the job's page (e.g. <job>/<job>_report.html); empty: no link
    std::string thumbnail;  ///< an image shown in the row; empty: none
};

/// Writes the index to `html_path` (atomically). Rows keep their order until a column is
/// clicked. Paths are linked relative to the page; a thumbnail that does not exist is an error
/// (tdf::Error naming it), a missing job page is shown as text without a link.
void write_batch_index(const std::string& html_path, const std::string& title,
                       const std::vector<BatchRow>& rows);

}  // namespace tdf
