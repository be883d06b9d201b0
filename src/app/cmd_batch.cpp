// `tdf batch grid|run|status|task`: many tdf jobs from a manifest, on this machine or as one
// Slurm job array (README "tdf batch").
#include <tdf/batch/batch_summary.h>
#include <tdf/batch/grid.h>
#include <tdf/batch/job_runner.h>
#include <tdf/batch/slurm_engine.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
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
    const bool csv = fs::path(o.grid_output).extension() == ".csv";
    write_text_atomically(o.grid_output, csv ? manifest_to_csv(jobs) : manifest_to_jsonl(jobs));
    log_info("wrote {} jobs to {} ({} scenes x {} textures x {} override sets)",
             jobs.size(),
             o.grid_output,
             o.grid.scenes.size(),
             std::max<std::size_t>(1, o.grid.textures.size()),
             std::max<std::size_t>(1, o.grid.override_sets.size()));
    return 0;
}

// Jobs that still have to run: neither done nor running elsewhere.
std::vector<std::size_t> jobs_to_run(const BatchFolder& folder) {
    std::vector<std::size_t> todo;
    for (std::size_t k = 0; k < folder.jobs().size(); ++k) {
        const JobStatus s = folder.read_state(folder.jobs()[k]).status;
        if (s != JobStatus::Done && s != JobStatus::Running) todo.push_back(k);
    }
    return todo;
}

int run_batch(const BatchOptions& o) {
    if (o.engine != "local" && o.engine != "slurm")
        throw_error("--engine must be local or slurm, not '{}'", o.engine);
    const std::vector<BatchJob> jobs = read_manifest(o.manifest);
    if (o.output.empty()) throw_error("-o/--output is empty: give the batch folder");
    // One `tdf batch run` per folder at a time (array tasks do not take this lock).
    const OutputFolderLock lock(o.output, "batch run");
    const BatchFolder folder =
        BatchFolder::create(o.output, jobs, this_executable(), fs::current_path().string());
    const std::vector<std::size_t> todo = jobs_to_run(folder);
    const BatchTotals before = batch_totals(folder);
    if (todo.empty()) {
        write_batch_summary(folder);
        log_info("{}: nothing to run ({} done, {} running)", folder.root(), before.done, before.running);
        return before.exit_code();
    }
    if (before.done + before.running > 0)
        log_info("{}: {} of {} jobs done, {} running elsewhere; running the other {}",
                 folder.root(),
                 before.done,
                 jobs.size(),
                 before.running,
                 todo.size());

    if (o.engine == "slurm") {
        const SlurmSubmission s = submit_slurm(folder, todo, o.slurm);
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
    log_info("{}: {} jobs, {} at a time, {} thread(s) each; logs in {}/logs",
             folder.root(),
             todo.size(),
             plan.parallel,
             plan.threads_per_job,
             folder.root());
    const JobRunOutcome outcome = run_jobs(folder, plan);
    write_batch_summary(folder);
    std::fputs(batch_status_table(folder).c_str(), stdout);
    if (outcome.stopped)
        log_info("stopped by a signal: {} job(s) not started; run the same command again to continue",
                 outcome.not_started);
    log_info("summary: {}/summary.csv and summary.json", folder.root());
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
    const JobRunOutcome outcome = run_jobs(folder, plan);
    return outcome.done == 1 ? 0 : outcome.interrupted == 1 ? kExitInterrupted : 1;
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

    CLI::App* run =
        app->add_subcommand("run", "run a manifest's jobs into a batch folder (only those not done)");
    run->add_option("manifest", o->manifest, "manifest (CSV or JSON lines)")
        ->required()
        ->check(CLI::ExistingFile);
    run->add_option("-o,--output", o->output, "batch folder (created; an existing one is continued)")
        ->required();
    run->add_option("--engine", o->engine, "local or slurm")->capture_default_str();
    run->add_option(
           "--jobs", o->jobs, "local: jobs at a time (0 = threads / threads-per-job, or one per thread)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option(
           "--threads-per-job", o->threads_per_job, "local: threads of each job (0 = an equal share)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option(
           "--max-parallel", o->slurm.max_parallel, "slurm: array tasks at a time, %K (0 = no limit)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    run->add_option(
           "--cpus-per-task", o->slurm.cpus_per_task, "slurm: --cpus-per-task (tdf threads follow it)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    run->add_option("--signal-seconds",
                    o->slurm.signal_seconds,
                    "slurm: seconds before the time limit at which a task checkpoints and requeues itself")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    run->add_option("--sbatch-option",
                    o->slurm.sbatch_options,
                    "slurm: an extra sbatch option, e.g. --sbatch-option=--partition=cpu; repeat")
        ->allow_extra_args(false);
    run->add_flag("--wait", o->slurm.wait, "slurm: return only when every task and the summary have ended");

    CLI::App* status =
        app->add_subcommand("status", "per job: done / running / failed (with the error line) / pending");
    status->add_option("folder", o->folder, "batch folder")->required();
    status->add_flag("--summary", o->summary, "also (re)write summary.json and summary.csv");
    status->add_flag("--json", o->json, "print the summary JSON instead of the table");

    CLI::App* task =
        app->add_subcommand("task", "run one job of a batch folder (what each Slurm array task runs)");
    task->add_option("folder", o->folder, "batch folder")->required();
    task->add_option("index", o->task_index, "job index (0-based, the manifest's order)")->required();

    for (CLI::App* sub : {grid, run, status, task}) sub->fallthrough();  // global flags may follow
    command.app = app;
    command.run = [o, grid, run, status, task]() -> int {
        if (grid->parsed()) return run_grid(*o);
        if (run->parsed()) return run_batch(*o);
        if (status->parsed()) return run_status(*o);
        if (task->parsed()) return run_task(*o);
        return 1;
    };
    return command;
}

}  // namespace tdf::app
