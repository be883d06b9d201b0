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
    /// A job that ends failed-resource is run again (at the end of the queue) until it has
    /// failed max_retries + 1 tries; failed-input is never retried.
    int max_retries = 2;
    /// Once this many jobs have failed for good in this call, no new job (nor retry) starts;
    /// the running ones finish. 0 = no cap.
    int max_failures = 0;
    /// A child still running after this many seconds gets SIGTERM (an optimize checkpoints),
    /// SIGKILL kTimeoutGraceSeconds later, and ends failed-resource. 0 = no limit.
    double timeout_seconds = 0;
};

/// Seconds between a timed-out child's SIGTERM and its SIGKILL.
constexpr double kTimeoutGraceSeconds = 10;

struct JobRunOutcome {
    int started = 0;  ///< attempts started (retries included)
    int done = 0;
    int failed = 0;        ///< jobs that failed for good (input, or resource with no retry left)
    int interrupted = 0;   ///< preempted: stopped by a signal, continued by the next run
    int retried = 0;       ///< attempts that failed for a resource and were run again
    int not_started = 0;   ///< planned jobs never started (stop signal or --max-failures)
    bool stopped = false;  ///< a stop signal arrived: no new job was started after it
    bool capped = false;   ///< max_failures was reached: no new job was started after it
};

/// Whether a job in `state` failed for good: failed-input, or failed-resource after
/// max_retries + 1 tries.
bool failed_for_good(const JobState& state, int max_retries);

/// The child's command line: `<tdf> --threads N <command> <args, {out} replaced> [...]`, adding
/// `-o <out>` for optimize/render when the args give no -o/--output, `--json` for compare, and
/// `--resume` for an optimize job whose folder holds a checkpoint but no completion record.
std::vector<std::string> job_command_line(const BatchFolder& folder, const BatchJob& job, int threads);

/// Runs the planned jobs, at most `plan.parallel` at a time, each child in its own process
/// group with stdout/stderr appended to the job's log (compare: stdout to `<out>/compare.json`),
/// writing the job's state when it starts and when it ends. A failing job does not stop the
/// others; resource failures are retried, failures are capped, children timed out (see
/// JobRunPlan). Each child gets TDF_BATCH_JOB=<name> and TDF_BATCH_ATTEMPT=<n> in its
/// environment. SIGTERM, SIGINT or SIGUSR1 to this process: no new job starts, SIGTERM is passed to
/// every running child (an optimize checkpoints at its next iteration and exits 75), and the
/// call returns once they have exited. Blocks those signals and SIGCHLD while it runs.
JobRunOutcome run_jobs(const BatchFolder& folder, const JobRunPlan& plan);

/// Reads what a finished job left (completion record, quality numbers, thumbnail) into `state`,
/// and decides done / failed / interrupted and the class (JobEnd) from the exit and the record;
/// counts the try unless preempted. `timed_out`: the runner stopped it at its --timeout.
void collect_job_result(const BatchFolder& folder, const BatchJob& job, int exit_code, int signal,
                        bool timed_out, const std::string& log_tail, JobState& state);

}  // namespace tdf
