#pragma once
/// What a batch did, per job and in total: `tdf batch status` and the summary files.
#include <tdf/batch/batch_folder.h>

#include <string>

namespace tdf {

/// Exit codes of `tdf batch run` and `tdf batch status` (docs/commands/batch.md).
constexpr int kBatchExitAllDone = 0;     ///< every job done
constexpr int kBatchExitBadInput = 1;    ///< bad manifest/options, a changed manifest, sbatch refused
constexpr int kBatchExitFailed = 2;      ///< at least one job failed
constexpr int kBatchExitUnfinished = 3;  ///< none failed, but some are pending, running or interrupted

struct BatchTotals {
    int pending = 0, running = 0, done = 0, failed = 0, interrupted = 0;
    int failed_input = 0, failed_resource = 0;  ///< the failed ones by class
    int total() const { return pending + running + done + failed + interrupted; }
    /// kBatchExitAllDone, kBatchExitFailed or kBatchExitUnfinished.
    int exit_code() const;
};

BatchTotals batch_totals(const BatchFolder& folder);

/// Everything a report page needs: {"batch", "written", "totals": {...}, "jobs": [{"job",
/// "command", "status", "class", "exit_code", "signal", "error", "attempts", "tries", "seconds",
/// "seconds_total", "started",
/// "finished", "host", "slurm_job", "output", "log", "thumbnail", "quality": {...}}]}. Paths
/// inside the batch folder are relative to it.
Json batch_summary_json(const BatchFolder& folder);

/// Writes `summary.json` and `summary.csv` (one row per job; quality numbers as columns
/// `quality.<key>`, the union over the jobs) into the batch folder, atomically.
void write_batch_summary(const BatchFolder& folder);

/// The table `tdf batch status` prints: one line per job (status, class, seconds, attempts,
/// tries, error line) and the totals, the failed ones by class.
std::string batch_status_table(const BatchFolder& folder);

}  // namespace tdf
