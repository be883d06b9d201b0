#pragma once
/// Running batch jobs as `tdf` child processes: the local engine (N at a time) and the body of a
/// Slurm array task (one) share this code.
#include <tdf/batch/batch_folder.h>

#include <cstddef>
#include <string>
#include <vector>

namespace tdf {

struct JobRunPlan {
    std::vector<std::size_t> indices;  ///< jobs to run, in this order
    int parallel = 1;                  ///< children at a time (>= 1)
    int threads_per_job = 1;           ///< `tdf --threads N` of each child (>= 1)
    /// Under Slurm: after a job stopped on a signal, requeue this array task with `scontrol
    /// requeue $SLURM_ARRAY_JOB_ID_$SLURM_ARRAY_TASK_ID` so that it continues later.
    bool requeue_interrupted = false;
};

struct JobRunOutcome {
    int done = 0, failed = 0, interrupted = 0, not_started = 0;
    bool stopped = false;  ///< a stop signal arrived: no new job was started after it
};

/// The child's command line: `<tdf> --threads N <command> <args, {out} replaced> [...]`, adding
/// `-o <out>` for optimize/render when the args give no -o/--output, `--json` for compare, and
/// `--resume` for an optimize job whose folder holds a checkpoint but no completion record.
std::vector<std::string> job_command_line(const BatchFolder& folder, const BatchJob& job, int threads);

/// Runs the planned jobs, at most `plan.parallel` at a time, each child in its own process
/// group with stdout/stderr appended to the job's log (compare: stdout to `<out>/compare.json`),
/// writing the job's state when it starts and when it ends. A failing job does not stop the
/// others. SIGTERM, SIGINT or SIGUSR1 to this process: no new job starts, SIGTERM is passed to
/// every running child (an optimize checkpoints at its next iteration and exits 75), and the
/// call returns once they have exited. Blocks those signals and SIGCHLD while it runs.
JobRunOutcome run_jobs(const BatchFolder& folder, const JobRunPlan& plan);

/// Reads what a finished job left (completion record, quality numbers, thumbnail) into `state`,
/// and decides done / failed / interrupted from the exit and the record.
void collect_job_result(const BatchFolder& folder, const BatchJob& job, int exit_code, int signal,
                        const std::string& log_tail, JobState& state);

}  // namespace tdf
