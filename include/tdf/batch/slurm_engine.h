#pragma once
/// The Slurm engine of `tdf batch run --engine slurm`: job arrays over the jobs that are not done
/// (one array, or several when there are more than the cluster's MaxArraySize, each after the
/// one before so that %K holds over all of them), plus one small job that depends on them
/// (`afterany`) and runs `tdf batch finish DIR`: it submits a retry round for the jobs that
/// failed for a resource and have tries left (more memory and time, failing nodes excluded),
/// with its own finish job, or else writes the summary. Slurm, not tdf, waits.
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
/// `DIR/slurm/array_<k>.sh` when there are several arrays (split, or retry groups).
/// `DIR/slurm/summary.sh`: `tdf batch finish DIR` after the arrays (afterany).
/// `DIR/slurm/options.json`: these options, for the retry rounds.
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
    int max_array_size = 0;        ///< split above this many indices; 0 = scontrol's MaxArraySize
    int max_retries = 2;           ///< tries after the first for failed-resource jobs (rounds)
    double retry_mem_factor = 1;   ///< a retry's --mem: the given --mem x factor^(tries so far)
    double retry_time_factor = 1;  ///< a retry's --time likewise

    Json to_json() const;
    static SlurmOptions from_json(const Json& json);
};

struct SlurmSubmission {
    std::string array_job;                ///< Slurm job id of the (first) array
    std::vector<std::string> array_jobs;  ///< every array, in order
    std::string summary_job;              ///< id of the dependent summary job
    std::string array_spec;               ///< the (first) --array value
};

/// The cluster's MaxArraySize (`scontrol show config`); Slurm's default 1001 when it cannot tell.
int slurm_max_array_size();

/// `indices` (sorted) cut into arrays whose task ids stay below `max_array_size`: each entry is
/// (base, the indices minus base), with base a multiple of max_array_size.
std::vector<std::pair<std::size_t, std::vector<std::size_t>>> split_array(
    const std::vector<std::size_t>& indices, int max_array_size);

/// `option` ("--mem=4G", "--time=1-02:00:00") scaled by `factor`: --mem in whole MB, --time in
/// whole minutes, rounded up; other options unchanged.
std::string scale_sbatch_option(const std::string& option, double factor);

/// "0-15%4", "1,3,5-7" (consecutive indices as ranges), "%K" only when max_parallel > 0.
std::string slurm_array_spec(const std::vector<std::size_t>& indices, int max_parallel);

/// The array task script for `indices` (task ids; task i runs job base + i).
std::string slurm_array_script(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                               const SlurmOptions& options, std::size_t base = 0);

/// Jobs that must be submitted with the same extra sbatch options.
struct SlurmJobGroup {
    std::vector<std::size_t> indices;
    std::vector<std::string> extra;  ///< scaled --mem/--time, --exclude
};

/// `indices` grouped by what their submission must add: a job that failed for a resource after
/// t tries gets the --mem/--time sbatch options scaled by factor^t and --exclude=<the nodes where
/// it failed for a resource twice or more>; other jobs nothing.
std::vector<SlurmJobGroup> slurm_job_groups(const BatchFolder& folder,
                                            const std::vector<std::size_t>& indices,
                                            const SlurmOptions& options);

/// Writes the scripts under DIR/slurm/ and options.json, submits the arrays of every group (one
/// after the other) and ONE finish job after all of them, and records them in
/// DIR/slurm/submissions.jsonl. Throws tdf::Error with sbatch's message when it refuses.
SlurmSubmission submit_slurm(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                             const SlurmOptions& options);

/// `tdf batch finish DIR`, first: waits while a job whose Slurm task requeued itself after an
/// interruption is still pending or running again (its state file says so and squeue still lists
/// the task), polling every 2 s for at most `max_seconds`; returns how many were still waited for
/// when it gave up (0: none left). Slurm can release the finish job's afterany dependency while a
/// task requeues itself; without this wait the batch would close with that job "interrupted".
int wait_for_requeued_jobs(const BatchFolder& folder, double max_seconds);

/// `tdf batch finish DIR` (the finish job): submits the jobs that failed for a resource and have
/// tries left (the options recorded in DIR/slurm/options.json) as a new round; returns how many.
int submit_retry_round(const BatchFolder& folder);

/// The finish job the latest submission recorded in DIR/slurm/submissions.jsonl, "" when none.
std::string latest_finish_job(const BatchFolder& folder);

/// Blocks until Slurm job `id` has ended: `sbatch --wait` of an empty job that depends on it.
void wait_for_slurm_job(const BatchFolder& folder, const SlurmOptions& options, const std::string& id);

}  // namespace tdf
