#pragma once
/// A batch folder (`tdf batch run MANIFEST -o DIR`) and the state of its jobs. Layout:
///
///   DIR/manifest.jsonl       the manifest it was made from (canonical JSON lines)
///   DIR/batch.json           tdf executable, working folder (relative paths in args), created
///   DIR/jobs/<name>/         a job's output folder (unless the manifest names another)
///   DIR/state/<name>.json    a job's state, written atomically by whoever runs it
///   DIR/logs/<name>.log      a job's stderr (and stdout), every attempt appended
///   DIR/logs/slurm-*.out     Slurm's own per-task output (slurm engine)
///   DIR/slurm/               the array script, the summary script, the submissions
///   DIR/summary.json, .csv   per job: status, error, times, quality numbers, thumbnail
#include <tdf/train/run_guard.h>  // utc_timestamp
#include <tdf/batch/manifest.h>

#include <string>
#include <vector>

namespace tdf {

/// pending: never started (or no state); running: a runner is on it; done: exited 0 with its
/// completion record; failed: non-zero exit, or its runner died (`error` says which);
/// interrupted: stopped by a signal (optimize: with a checkpoint) and will continue.
enum class JobStatus { Pending, Running, Done, Failed, Interrupted };

const char* job_status_name(JobStatus status);

/// How a job's last attempt ended (state key "class"; docs/commands/batch.md "Failure classes"):
/// done; failed-input: deterministic (tdf exit 1, a bad mesh or scene, or any exit code not
/// listed below), never retried; failed-resource: out of memory (exit kExitOutOfMemory or
/// SIGKILL), the --timeout, a signal other than the stop signals, an unexpected error (exit
/// kExitUnexpected: a system error or a bug), a runner or node that died: retried up to --max-retries
/// times; preempted: stopped by SIGTERM/SIGINT/SIGUSR1 or exit kExitInterrupted (requeued or
/// continued by the next run, not counted as a try). None while pending or running.
enum class JobEnd { None, Done, FailedInput, FailedResource, Preempted };

const char* job_end_name(JobEnd end);

/// The class of a process end that is not a success: `timed_out` when the runner stopped it at
/// its --timeout.
JobEnd classify_job_end(int exit_code, int signal, bool timed_out);

/// The status an ended attempt leaves: done; failed (input or resource); interrupted (preempted).
JobStatus status_after(JobEnd end);

struct JobState {
    JobStatus status = JobStatus::Pending;
    JobEnd end = JobEnd::None;      ///< how the last attempt ended (key "class")
    int exit_code = -1;             ///< the tdf process's exit code, -1 when none
    int signal = 0;                 ///< terminating signal, 0 when none
    std::string error;              ///< the error line (last "tdf ..." line of the log) for failed jobs
    int attempts = 0;               ///< starts, including requeues and resumed runs
    int tries = 0;                  ///< attempts that ended done or failed (preempted ones do not count)
    double seconds = 0;             ///< wall time of the last attempt
    double seconds_total = 0;       ///< wall time of all attempts
    std::string started, finished;  ///< UTC ISO 8601
    std::string host;
    std::vector<std::string> failed_hosts;  ///< the host of each failed-resource try
    int pid = 0;               ///< the runner's pid while running
    std::string slurm_job;     ///< "<array job>_<task>" under Slurm
    bool requeued = false;     ///< an interrupted Slurm task asked Slurm to run it again
    std::string command_line;  ///< the tdf command of the last attempt
    std::string output;        ///< absolute output folder
    std::string thumbnail;     ///< a PNG the job produced (path relative to the batch folder), or ""
    Json quality =
        Json::object();  ///< the job's quality numbers (optimize: held-out report; compare: PSNR, ...)

    /// Records how the attempt ended: `end` and the status it implies, always together (the state
    /// file keeps both keys, "status" and "class", for its readers).
    void end_attempt(JobEnd how) {
        end = how;
        status = status_after(how);
    }

    Json to_json() const;
    static JobState from_json(const Json& json);
};

class BatchFolder {
public:
    /// Opens `root` for `jobs`. With `create`: makes the folder and records the manifest, or,
    /// when it exists, refuses (tdf::Error) a manifest that differs from the recorded one, naming
    /// what changed. Without: the folder must exist; `jobs` is ignored and the recorded manifest
    /// is read. `tdf_executable` and `working_folder` are recorded on creation and read otherwise.
    static BatchFolder create(const std::string& root, const std::vector<BatchJob>& jobs,
                              const std::string& tdf_executable, const std::string& working_folder);
    static BatchFolder open(const std::string& root);

    const std::string& root() const { return m_root; }
    const std::vector<BatchJob>& jobs() const { return m_jobs; }
    const std::string& tdf_executable() const { return m_tdf; }
    const std::string& working_folder() const { return m_working_folder; }

    /// Index of the job called `name`; throws when there is none.
    std::size_t index_of(const std::string& name) const;
    /// Absolute output folder of a job.
    std::string output_folder(const BatchJob& job) const;
    std::string state_path(const BatchJob& job) const;
    std::string log_path(const BatchJob& job) const;
    std::string path(const std::string& relative) const;

    /// The recorded state; a `running` state whose runner is known to be gone (same host, pid
    /// not alive) reads as failed with "the runner stopped without recording a result".
    JobState read_state(const BatchJob& job) const;
    void write_state(const BatchJob& job, const JobState& state) const;

private:
    std::string m_root, m_tdf, m_working_folder;
    std::vector<BatchJob> m_jobs;
};

/// This machine's host name.
std::string host_name();

/// Whether Slurm still knows the array task `id` ("123_4"): false only when squeue answered and
/// did not list it (a node failure or SIGKILL left a "running" state behind; a task that ended
/// long ago). `scratch`: a folder for squeue's output. True when there is no squeue to ask.
bool slurm_task_alive(const std::string& id, const std::string& scratch);

}  // namespace tdf
