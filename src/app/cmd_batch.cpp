// `tdf batch grid|run|status|task`: many tdf jobs from a manifest, on this machine or as one
// Slurm job array (docs/commands/batch.md).
#include <sys/resource.h>
#include <tdf/batch/batch_summary.h>
#include <tdf/batch/grid.h>
#include <tdf/batch/job_runner.h>
#include <tdf/batch/slurm_engine.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/train/run_guard.h>

#include <cstdio>
#include <filesystem>

#include "commands.h"

namespace tdf::app {

namespace {

namespace fs = std::filesystem;

struct BatchOptions {
    // grid
    GridSpec grid;
    std::string grid_output;
    // run
    std::string manifest;
    std::string output;
    std::string engine = "local";
    int jobs = 0;
    int threads_per_job = 0;
    int max_retries = 2;
    int max_failures = 0;
    double timeout = 0;
    bool retry_failed = false;
    SlurmOptions slurm;
    // status / task
    std::string folder;
    bool summary = false;
    bool json = false;
    std::size_t task_index = 0;
};

std::string this_executable() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    return ec ? std::string("tdf") : exe.string();
}

int run_grid(const BatchOptions& o) {
    const std::vector<BatchJob> jobs = make_grid(o.grid);
    const bool csv = lower_extension(o.grid_output) == ".csv";  // as every other output name: any case
    write_text_atomically(o.grid_output, csv ? manifest_to_csv(jobs) : manifest_to_jsonl(jobs));
    log_info("wrote {} jobs to {} ({} scenes x {} textures x {} override sets)",
             jobs.size(),
             o.grid_output,
             o.grid.scenes.size(),
             std::max<std::size_t>(1, o.grid.textures.size()),
             std::max<std::size_t>(1, o.grid.override_sets.size()));
    return 0;
}

// Jobs that still have to run: neither done, nor running elsewhere, nor failed for good (a
// failed-input job would fail the same way again; `--retry-failed` runs those too, e.g. after
// fixing an input).
std::vector<std::size_t> jobs_to_run(const BatchFolder& folder, int max_retries, bool retry_failed) {
    std::vector<std::size_t> todo;
    for (std::size_t k = 0; k < folder.jobs().size(); ++k) {
        const JobState s = folder.read_state(folder.jobs()[k]);
        if (s.status == JobStatus::Done || s.status == JobStatus::Running) continue;
        if (!retry_failed && failed_for_good(s, max_retries)) continue;
        todo.push_back(k);
    }
    return todo;
}

// --retry-failed: the jobs failed for good start over with a fresh count of tries.
void reset_tries(const BatchFolder& folder, const std::vector<std::size_t>& todo, int max_retries) {
    for (std::size_t k : todo) {
        const BatchJob& job = folder.jobs()[k];
        JobState s = folder.read_state(job);
        if (!failed_for_good(s, max_retries)) continue;
        s.tries = 0;
        folder.write_state(job, s);
    }
}

int run_batch(const BatchOptions& o) {
    // Each Slurm task runs one job: there is no runner to cap or time jobs across the array.
    if (o.engine == "slurm" && (o.timeout > 0 || o.max_failures > 0))
        throw_error(
            "--timeout and --max-failures apply to --engine local; under Slurm give "
            "--sbatch-option=--time=... (Slurm enforces it; --signal-seconds warns the task)");
    // Every problem a row can have is found here, before anything is written or launched.
    const std::vector<BatchJob> jobs = read_manifest(o.manifest);
    check_job_inputs(jobs, fs::current_path().string());
    if (o.output.empty()) throw_error("-o/--output is empty: give the batch folder");
    // One `tdf batch run` per folder at a time (array tasks do not take this lock).
    const OutputFolderLock lock(o.output, "batch run");
    const BatchFolder folder =
        BatchFolder::create(o.output, jobs, this_executable(), fs::current_path().string());
    const std::vector<std::size_t> todo = jobs_to_run(folder, o.max_retries, o.retry_failed);
    const BatchTotals before = batch_totals(folder);
    if (todo.empty()) {
        write_batch_summary(folder);
        log_info("{}: nothing to run ({} done, {} running, {} failed for good{})",
                 folder.root(),
                 before.done,
                 before.running,
                 before.failed,
                 before.failed > 0 ? "; --retry-failed runs those again" : "");
        return before.exit_code();
    }
    if (o.retry_failed) reset_tries(folder, todo, o.max_retries);
    if (todo.size() < jobs.size())
        log_info("{}: {} of {} jobs done, {} running elsewhere, {} failed for good; running the other {}",
                 folder.root(),
                 before.done,
                 jobs.size(),
                 before.running,
                 o.retry_failed ? 0 : before.failed,
                 todo.size());

    if (o.engine == "slurm") {
        SlurmOptions slurm = o.slurm;
        slurm.max_retries = o.max_retries;
        const SlurmSubmission s = submit_slurm(folder, todo, slurm);
        if (!o.slurm.wait) {
            log_info("follow it with `tdf batch status {}` (squeue -j {})", folder.root(), s.array_job);
            return 0;
        }
        const BatchTotals t = batch_totals(folder);
        std::fputs(batch_status_table(folder).c_str(), stdout);
        return t.exit_code();
    }

    const int total_threads = std::max(1, ThreadLimit::current());
    int parallel = o.jobs > 0              ? o.jobs
                   : o.threads_per_job > 0 ? std::max(1, total_threads / o.threads_per_job)
                                           : total_threads;
    parallel = std::max(1, std::min(parallel, int(todo.size())));
    JobRunPlan plan;
    plan.indices = todo;
    plan.parallel = parallel;
    plan.threads_per_job = o.threads_per_job > 0 ? o.threads_per_job : std::max(1, total_threads / parallel);
    plan.max_retries = o.max_retries;
    plan.max_failures = o.max_failures;
    plan.timeout_seconds = o.timeout;
    log_info("{}: {} jobs, {} at a time, {} thread(s) each; logs in {}/logs",
             folder.root(),
             todo.size(),
             plan.parallel,
             plan.threads_per_job,
             folder.root());
    const JobRunOutcome outcome = run_jobs(folder, plan);
    write_batch_summary(folder);
    std::fputs(batch_status_table(folder).c_str(), stdout);
    if (outcome.stopped || outcome.capped)
        log_info("{}: {} job(s) not started; run the same command again to continue",
                 outcome.stopped ? "stopped by a signal" : "--max-failures reached",
                 outcome.not_started);
    log_info("summary: {}/summary.csv and summary.json", folder.root());
    // The scheduler's own cost (this process, not its children): what bench/batch_1000.sh reports.
    rusage self{};
    getrusage(RUSAGE_SELF, &self);
    const double cpu = double(self.ru_utime.tv_sec + self.ru_stime.tv_sec) +
                       1e-6 * double(self.ru_utime.tv_usec + self.ru_stime.tv_usec);
    log_info("tdf batch's own CPU time: {:.2f} s for {} job start(s), {:.1f} ms each",
             cpu,
             outcome.started,
             1000 * cpu / std::max(1, outcome.started));
    return batch_totals(folder).exit_code();
}

int run_status(const BatchOptions& o) {
    const BatchFolder folder = BatchFolder::open(o.folder);
    if (o.summary) write_batch_summary(folder);
    if (o.json)
        std::printf("%s\n", batch_summary_json(folder).dump(2).c_str());
    else
        std::fputs(batch_status_table(folder).c_str(), stdout);
    return batch_totals(folder).exit_code();
}

// How long the finish job waits for tasks that requeued themselves to run again: long enough for
// Slurm's hold on a requeued job (about 2 minutes) and a resumed run, bounded so that a task held
// in the queue does not keep the finish job (one CPU) forever.
constexpr double kFinishWaitSeconds = 30 * 60;

// What the Slurm finish job runs once every array task has ended.
int run_finish(const BatchOptions& o) {
    const BatchFolder folder = BatchFolder::open(o.folder);
    wait_for_requeued_jobs(folder, kFinishWaitSeconds);
    const int resubmitted = submit_retry_round(folder);
    write_batch_summary(folder);
    std::fputs(batch_status_table(folder).c_str(), stdout);
    if (resubmitted > 0) {
        log_info("{} job(s) resubmitted for a resource failure; the summary follows their round",
                 resubmitted);
        return 0;
    }
    return batch_totals(folder).exit_code();
}

int run_task(const BatchOptions& o) {
    const BatchFolder folder = BatchFolder::open(o.folder);
    if (o.task_index >= folder.jobs().size())
        throw_error(
            "task {} is out of range: '{}' has {} jobs", o.task_index, folder.root(), folder.jobs().size());
    const BatchJob& job = folder.jobs()[o.task_index];
    if (folder.read_state(job).status == JobStatus::Done) {
        log_info("job {} is done already", job.name);
        return 0;
    }
    JobRunPlan plan;
    plan.indices = {o.task_index};
    plan.parallel = 1;
    plan.threads_per_job = std::max(1, ThreadLimit::current());  // SLURM_CPUS_PER_TASK
    plan.requeue_interrupted = std::getenv("SLURM_JOB_ID") != nullptr;
    // A retry under Slurm is a new submission (more memory or time, another node), not another
    // try inside this allocation, which would meet the same limits.
    plan.max_retries = 0;
    const JobRunOutcome outcome = run_jobs(folder, plan);
    return outcome.done == 1 ? 0 : outcome.interrupted == 1 ? kExitInterrupted : 1;
}

// `tdf batch run` and its options: the engine, retries and caps, and the Slurm settings.
CLI::App* add_run_subcommand(CLI::App* app, BatchOptions& o) {
    CLI::App* run =
        app->add_subcommand("run", "run a manifest's jobs into a batch folder (only those not done)");
    run->add_option("manifest", o.manifest, "manifest (CSV or JSON lines)")
        ->required()
        ->check(CLI::ExistingFile);
    run->add_option("-o,--output", o.output, "batch folder (created; an existing one is continued)")
        ->required();
    run->add_option("--engine", o.engine, "local or slurm")
        ->check(CLI::IsMember({"local", "slurm"}))
        ->capture_default_str();
    run->add_option(
           "--jobs", o.jobs, "local: jobs at a time (0 = threads / threads-per-job, or one per thread)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option(
           "--threads-per-job", o.threads_per_job, "local: threads of each job (0 = an equal share)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option("--max-retries",
                    o.max_retries,
                    "tries after the first for a job that failed for a resource (out of memory, "
                    "killed, timed out); bad input is never retried")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option("--max-failures",
                    o.max_failures,
                    "start no new job once this many have failed for good in this run (0 = no cap); "
                    "the rest stay pending for the next run")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option("--timeout",
                    o.timeout,
                    "local: seconds a job may run before SIGTERM (an optimize checkpoints), SIGKILL 10 s "
                    "later; ends failed-resource (0 = none)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_flag("--retry-failed",
                  o.retry_failed,
                  "also run jobs that failed for good in earlier runs (e.g. after fixing an input), "
                  "with a fresh count of tries");
    run->add_option(
           "--max-parallel", o.slurm.max_parallel, "slurm: array tasks at a time, %K (0 = no limit)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option("--max-array-size",
                    o.slurm.max_array_size,
                    "slurm: split into arrays of task ids below this (0 = the cluster's MaxArraySize)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option("--retry-mem-factor",
                    o.slurm.retry_mem_factor,
                    "slurm: a retry's --mem (from --sbatch-option=--mem=...) times this per failed try")
        ->check(CLI::Range(1.0, 100.0))
        ->capture_default_str();
    run->add_option("--retry-time-factor",
                    o.slurm.retry_time_factor,
                    "slurm: a retry's --time (from --sbatch-option=--time=...) times this per failed try")
        ->check(CLI::Range(1.0, 100.0))
        ->capture_default_str();
    run->add_option(
           "--cpus-per-task", o.slurm.cpus_per_task, "slurm: --cpus-per-task (tdf threads follow it)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    run->add_option("--signal-seconds",
                    o.slurm.signal_seconds,
                    "slurm: seconds before the time limit at which a task checkpoints and requeues itself")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    run->add_option("--sbatch-option",
                    o.slurm.sbatch_options,
                    "slurm: an extra sbatch option, e.g. --sbatch-option=--partition=cpu; repeat")
        ->allow_extra_args(false);
    run->add_flag("--wait", o.slurm.wait, "slurm: return only when every task and the summary have ended");
    return run;
}

}  // namespace

Command register_batch(CLI::App& root) {
    auto o = std::make_shared<BatchOptions>();
    Command command;
    CLI::App* app =
        root.add_subcommand("batch", "run many tdf jobs from a manifest, locally or as a Slurm job array");
    app->require_subcommand(1);

    CLI::App* grid = app->add_subcommand(
        "grid", "write a manifest: every scene/mesh x every tactile texture x every override set");
    grid->add_option("--scene", o->grid.scenes, "scene file (.json) or mesh (.obj/.gltf/.glb/.ply); repeat")
        ->required();
    grid->add_option("--texture", o->grid.textures, "tactile normal map; repeat (default: the scene's own)");
    grid->add_option("--overrides",
                     o->grid.override_sets,
                     "one override set, e.g. \"seed=1 optimize.iterations=100\"; repeat (default: none)");
    grid->add_option("--base-scene", o->grid.base_scene, "scene file meshes are placed in (mesh=<path>)");
    grid->add_option("--command", o->grid.command, "optimize or render")->capture_default_str();
    grid->add_option("-o,--output", o->grid_output, "manifest to write (.jsonl or .csv)")->required();

    CLI::App* run = add_run_subcommand(app, *o);

    CLI::App* status =
        app->add_subcommand("status", "per job: done / running / failed (with the error line) / pending");
    status->add_option("folder", o->folder, "batch folder")->required();
    status->add_flag("--summary", o->summary, "also (re)write summary.json and summary.csv");
    status->add_flag("--json", o->json, "print the summary JSON instead of the table");

    CLI::App* finish = app->add_subcommand(
        "finish",
        "after a Slurm submission (its finish job): resubmit resource failures with tries left, "
        "write the summary");
    finish->add_option("folder", o->folder, "batch folder")->required();

    CLI::App* task =
        app->add_subcommand("task", "run one job of a batch folder (what each Slurm array task runs)");
    task->add_option("folder", o->folder, "batch folder")->required();
    task->add_option("index", o->task_index, "job index (0-based, the manifest's order)")->required();

    for (CLI::App* sub : {grid, run, status, finish, task}) sub->fallthrough();  // global flags may follow
    command.app = app;
    command.run = [o, grid, run, status, finish, task]() -> int {
        if (grid->parsed()) return run_grid(*o);
        if (run->parsed()) return run_batch(*o);
        if (status->parsed()) return run_status(*o);
        if (finish->parsed()) return run_finish(*o);
        if (task->parsed()) return run_task(*o);
        return 1;
    };
    return command;
}

}  // namespace tdf::app
