#pragma once
/// The Slurm engine of `tdf batch run --engine slurm`: ONE job array over the jobs that are not
/// done, plus one small summary job that depends on it (`afterany`), so Slurm, not tdf, waits.
///
/// `DIR/slurm/array.sh` (each task: `tdf batch task DIR $SLURM_ARRAY_TASK_ID`):
///   --array=<indices>%K   the jobs to run (0-(N-1) on a first run), at most K at a time
///   --cpus-per-task=C     tdf's threads follow SLURM_CPUS_PER_TASK
///   --output=DIR/logs/slurm-%A_%a.out --open-mode=append   per-task logs, kept across requeues
///   --requeue             preempted or failed-node tasks go back to the queue
///   --signal=B:USR1@S     S seconds before the time limit the task runner is told to stop: the
///                         tdf job checkpoints at its next iteration, and the runner requeues the
///                         task (`scontrol requeue`), which continues with --resume
///   --chdir               the folder `tdf batch run` was started in (relative paths in args)
/// `DIR/slurm/summary.sh`: `tdf batch status DIR --summary` after the array (afterany).
/// Extra sbatch options (partition, account, time, memory, ...) are passed to both submissions.
#include <tdf/batch/batch_folder.h>

#include <cstddef>
#include <string>
#include <vector>

namespace tdf {

struct SlurmOptions {
    int max_parallel = 0;                     ///< K in %K: tasks at a time, 0 = as many as Slurm allows
    int cpus_per_task = 1;                    ///< --cpus-per-task
    int signal_seconds = 120;                 ///< --signal=B:USR1@S lead time before the time limit
    std::vector<std::string> sbatch_options;  ///< passed through to sbatch (e.g. --partition=cpu)
    bool wait = false;  ///< block (sbatch --wait on the summary job) until everything ended
    std::string sbatch = "sbatch";
};

struct SlurmSubmission {
    std::string array_job;       ///< Slurm job id of the array
    std::string summary_job;     ///< id of the dependent summary job
    std::string array_spec;      ///< the --array value
    int summary_exit_code = -1;  ///< with `wait`: the summary job's exit code (batch status exit code)
};

/// "0-15%4", "1,3,5-7" (consecutive indices as ranges), "%K" only when max_parallel > 0.
std::string slurm_array_spec(const std::vector<std::size_t>& indices, int max_parallel);

/// The array task script for `indices`.
std::string slurm_array_script(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                               const SlurmOptions& options);

/// Writes the scripts under DIR/slurm/, submits the array and the summary job, and records both
/// in DIR/slurm/submissions.jsonl. Throws tdf::Error with sbatch's message when it refuses.
SlurmSubmission submit_slurm(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                             const SlurmOptions& options);

}  // namespace tdf
