#include <signal.h>
#include <sys/wait.h>
#include <tdf/batch/job_runner.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/guidance/subprocess.h>
#include <tdf/train/run_guard.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>

namespace tdf {

namespace fs = std::filesystem;

namespace {

bool has_argument(const std::vector<std::string>& args, std::initializer_list<const char*> names) {
    for (const std::string& a : args)
        for (const char* n : names)
            if (a == n || a.rfind(std::string(n) + "=", 0) == 0) return true;
    return false;
}

// The completion records in a job's folder (optimize: <name>_complete.json; render: render_complete.json).
std::vector<fs::path> completion_records(const std::string& out) {
    std::vector<fs::path> records;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(out, ec)) {
        const std::string file = entry.path().filename().string();
        if (file.size() > 14 && file.compare(file.size() - 14, 14, "_complete.json") == 0)
            records.push_back(entry.path());
    }
    std::sort(records.begin(), records.end());
    return records;
}

// Text of `path` after byte `offset` (this attempt's part of an appended log).
std::string read_from(const std::string& path, std::uintmax_t offset) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    in.seekg(std::streamoff(offset));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The error line: the last line main() printed ("tdf <command>: ..."), else the last line.
std::string error_line(const std::string& log) {
    std::string last, last_tdf;
    std::size_t start = 0;
    while (start < log.size()) {
        std::size_t end = log.find('\n', start);
        if (end == std::string::npos) end = log.size();
        std::string line = log.substr(start, end - start);
        start = end + 1;
        // Progress bars redraw with \r: keep the last state.
        if (const auto cr = line.rfind('\r'); cr != std::string::npos) line = line.substr(cr + 1);
        if (line.find_first_not_of(" \t") == std::string::npos) continue;
        last = line;
        if (line.rfind("tdf ", 0) == 0) last_tdf = line;
    }
    return last_tdf.empty() ? last : last_tdf;
}

std::string relative_to_batch(const BatchFolder& folder, const fs::path& p) {
    const std::string s = p.lexically_normal().string();
    const std::string root = folder.root() + "/";
    return s.rfind(root, 0) == 0 ? s.substr(root.size()) : s;
}

std::string find_thumbnail(const BatchFolder& folder, const std::string& out) {
    for (const char* candidate : {"turntable/lambertian_000.png",
                                  "turntable/albedo_000.png",
                                  "view_000_lambertian.png",
                                  "view_000_albedo.png"})
        if (fs::exists(fs::path(out) / candidate))
            return relative_to_batch(folder, fs::path(out) / candidate);
    std::vector<fs::path> pngs;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(out, ec))
        if (entry.path().extension() == ".png" && !is_atomic_temporary(entry.path().filename().string()))
            pngs.push_back(entry.path());
    std::sort(pngs.begin(), pngs.end());
    return pngs.empty() ? std::string() : relative_to_batch(folder, pngs.front());
}

}  // namespace

std::vector<std::string> job_command_line(const BatchFolder& folder, const BatchJob& job, int threads) {
    const std::string out = folder.output_folder(job);
    std::vector<std::string> argv = {
        folder.tdf_executable(), "--threads", std::to_string(std::max(1, threads)), job.command};
    for (std::string a : job.args) {
        for (std::size_t at = a.find("{out}"); at != std::string::npos; at = a.find("{out}", at + out.size()))
            a.replace(at, 5, out);
        argv.push_back(a);
    }
    if ((job.command == "optimize" || job.command == "render") &&
        !has_argument(job.args, {"-o", "--output"})) {
        argv.push_back("-o");
        argv.push_back(out);
    }
    if (job.command == "compare" && !has_argument(job.args, {"--json"})) argv.push_back("--json");
    if (job.command == "optimize" && !has_argument(job.args, {"--resume"}) &&
        fs::exists(out + "/checkpoint.bin") && completion_records(out).empty())
        argv.push_back("--resume");
    return argv;
}

bool failed_for_good(const JobState& state, int max_retries) {
    return state.status == JobStatus::Failed &&
           (state.end != JobEnd::FailedResource || state.tries > max_retries);
}

void collect_job_result(const BatchFolder& folder, const BatchJob& job, int exit_code, int signal,
                        bool timed_out, const std::string& log_tail, JobState& state) {
    const std::string out = folder.output_folder(job);
    state.exit_code = exit_code;
    state.signal = signal;
    state.error.clear();
    state.quality = Json::object();
    const auto records = completion_records(out);
    const bool needs_record = job.command == "optimize" || job.command == "render";
    if (!timed_out && exit_code == 0 && (!needs_record || !records.empty())) {
        state.end_attempt(JobEnd::Done);
    } else if (!timed_out && exit_code == 0) {
        state.end_attempt(JobEnd::Preempted);
        state.error = "exited without a completion record (--stop-after?); the next run continues it";
    } else {
        state.end_attempt(classify_job_end(exit_code, signal, timed_out));
        state.error = error_line(log_tail);
        if (state.end == JobEnd::Preempted) {
            if (state.error.empty()) state.error = "stopped by " + signal_name(signal);
        } else {
            if (timed_out)
                state.error = fmt::format("timed out after {:.0f} s (--timeout){}",
                                          state.seconds,
                                          state.error.empty() ? "" : ": " + state.error);
            else if (signal != 0)
                state.error =
                    "killed by " + signal_name(signal) + (state.error.empty() ? "" : ": " + state.error);
            if (state.error.empty()) state.error = "exit code " + std::to_string(exit_code);
        }
    }
    if (state.end != JobEnd::Preempted) state.tries += 1;
    // Under Slurm, a node where a job failed twice for a resource is excluded on its retry.
    if (state.end == JobEnd::FailedResource) state.failed_hosts.push_back(state.host);
    // Quality numbers, whatever the status (a failed compare still measured its images).
    try {
        if (job.command == "optimize" && !records.empty()) {
            const Json record = load_json_file(records.front().string());
            const std::string report = out + "/" + record.value("report", std::string());
            if (fs::is_regular_file(report)) {
                const Json r = load_json_file(report);
                if (r.contains("quality")) state.quality = r["quality"];
            }
        } else if (job.command == "render" && !records.empty()) {
            const Json record = load_json_file(records.front().string());
            if (record.contains("views")) state.quality["views"] = record["views"];
        } else if (job.command == "compare" && fs::exists(out + "/compare.json")) {
            const Json r = parse_json(read_text_file(out + "/compare.json"), out + "/compare.json");
            state.quality["result"] = r.value("result", std::string());
            if (r.contains("overall")) {
                for (const char* key : {"psnr", "rms_error", "max_error", "mean_error"})
                    if (r["overall"].contains(key)) state.quality[key] = r["overall"][key];
            }
            if (r.contains("fail_percent")) state.quality["fail_percent"] = r["fail_percent"];
        }
    } catch (const Error& e) {
        log_warning("job '{}': cannot read its quality numbers: {}", job.name, e.what());
    }
    state.thumbnail = find_thumbnail(folder, out);
}

namespace {

struct RunningJob {
    std::size_t index;
    JobState state;
    std::uintmax_t log_offset;
    std::chrono::steady_clock::time_point start;
    bool timed_out = false;  ///< SIGTERM sent at the --timeout; SIGKILL follows after the grace
};

// Asks Slurm to run this array task again; returns whether it accepted.
bool requeue_this_task() {
    const char* array_job = std::getenv("SLURM_ARRAY_JOB_ID");
    const char* task = std::getenv("SLURM_ARRAY_TASK_ID");
    const char* job = std::getenv("SLURM_JOB_ID");
    const std::string id = array_job && task ? std::string(array_job) + "_" + task : job ? job : "";
    if (id.empty()) return false;
    try {
        const ProcessOutcome outcome = run_process({"scontrol", "requeue", id}, "", 60, "", "");
        if (outcome.exit_code == 0) {
            log_info("requeued Slurm task {}: it continues from its checkpoint when it runs again", id);
            return true;
        }
        log_warning("scontrol requeue {} failed (exit {}); Slurm may requeue it itself (preemption)",
                    id,
                    outcome.exit_code);
    } catch (const Error& e) {
        log_warning("cannot requeue Slurm task {}: {}", id, e.what());
    }
    return false;
}

}  // namespace

namespace {

using Clock = std::chrono::steady_clock;

Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// One run_jobs call: the queue, the running children and the counts, and the four things that
// happen to them (a job starts, ends and is counted; a timeout comes due).
struct JobLoop {
    const BatchFolder& folder;
    const JobRunPlan& plan;
    JobRunOutcome outcome;
    std::map<pid_t, RunningJob> running;
    std::deque<std::size_t> queue;
    const char* array_job = std::getenv("SLURM_ARRAY_JOB_ID");
    const char* array_task = std::getenv("SLURM_ARRAY_TASK_ID");

    JobLoop(const BatchFolder& f, const JobRunPlan& p)
        : folder(f), plan(p), queue(p.indices.begin(), p.indices.end()) {}

    void account(const BatchJob& job, std::size_t index, const JobState& state);
    void start_job(std::size_t index);
    void finish_job(pid_t pid, int status);
    Clock::time_point enforce_timeouts();
    void run(const sigset_t& waited);
};

// After an attempt's state is written: count it, and queue a resource failure again while it
// has tries left (unless starting has stopped: the next run continues it then).
void JobLoop::account(const BatchJob& job, std::size_t index, const JobState& state) {
    switch (state.status) {
        case JobStatus::Done:
            ++outcome.done;
            log_info("done {} in {:.1f} s", job.name, state.seconds);
            return;
        case JobStatus::Interrupted:
            ++outcome.interrupted;
            log_info("interrupted {}: {}", job.name, state.error);
            if (plan.requeue_interrupted) {
                // Recorded before asking: Slurm may end this runner as it requeues the task, and
                // the finish job must know that the job will run again (wait_for_requeued_jobs).
                JobState requeued = state;
                requeued.requeued = true;
                folder.write_state(job, requeued);
                if (!requeue_this_task()) folder.write_state(job, state);
            }
            return;
        default:
            break;
    }
    if (!failed_for_good(state, plan.max_retries)) {
        if (outcome.stopped || outcome.capped) {
            ++outcome.not_started;
            log_warning("failed {} ({}): {}; not retried now, the next run does",
                        job.name,
                        job_end_name(state.end),
                        state.error);
        } else {
            ++outcome.retried;
            queue.push_back(index);
            log_warning("failed {} ({}, try {} of {}): {}; retrying",
                        job.name,
                        job_end_name(state.end),
                        state.tries,
                        plan.max_retries + 1,
                        state.error);
        }
        return;
    }
    ++outcome.failed;
    log_warning("failed {} ({}): {}", job.name, job_end_name(state.end), state.error);
    if (plan.max_failures > 0 && outcome.failed >= plan.max_failures && !outcome.capped) {
        outcome.capped = true;
        log_warning(
            "{} job(s) failed for good (--max-failures {}): starting no new job; the "
            "next run continues the rest",
            outcome.failed,
            plan.max_failures);
    }
}

void JobLoop::start_job(std::size_t index) {
    const BatchJob& job = folder.jobs()[index];
    JobState state = folder.read_state(job);
    state.status = JobStatus::Running;
    state.end = JobEnd::None;
    state.attempts += 1;
    state.host = host_name();
    state.pid = getpid();
    state.started = utc_timestamp();
    state.finished.clear();
    state.requeued = false;
    state.error.clear();
    state.exit_code = -1;
    state.signal = 0;
    state.slurm_job = array_job && array_task ? std::string(array_job) + "_" + array_task : "";
    state.output = folder.output_folder(job);
    const std::vector<std::string> argv = job_command_line(folder, job, plan.threads_per_job);
    state.command_line = format_command(argv);
    ensure_folder(state.output);
    const std::string log = folder.log_path(job);
    ensure_folder(fs::path(log).parent_path().string());
    {
        std::ofstream header(log, std::ios::app);
        header << "=== tdf batch: job " << job.name << ", attempt " << state.attempts << " on "
               << state.host << " at " << state.started
               << (state.slurm_job.empty() ? "" : ", Slurm " + state.slurm_job) << "\n"
               << "=== " << state.command_line << "\n";
    }
    std::error_code ec;
    const std::uintmax_t offset = fs::file_size(log, ec);
    folder.write_state(job, state);
    const std::string stdout_path = job.command == "compare" ? state.output + "/compare.json" : log;
    // The child inherits these (fork): it may name itself in its own files, and the test-only
    // TDF_TEST_KILL_JOBS (main.cpp) picks its victims by them.
    setenv("TDF_BATCH_JOB", job.name.c_str(), 1);
    setenv("TDF_BATCH_ATTEMPT", std::to_string(state.attempts).c_str(), 1);
    try {
        const pid_t pid =
            spawn_process(argv, folder.working_folder(), stdout_path, log, job.command != "compare");
        running[pid] = RunningJob{index, state, ec ? 0 : offset, Clock::now()};
        ++outcome.started;
        log_info("started {} ({} of {}): {}",
                 job.name,
                 outcome.done + outcome.failed + outcome.interrupted + int(running.size()),
                 plan.indices.size(),
                 state.command_line);
    } catch (const Error& e) {
        // fork or exec failed: the machine's doing (process limit, memory), not the job's.
        state.end_attempt(JobEnd::FailedResource);
        state.tries += 1;
        state.failed_hosts.push_back(state.host);
        state.error = e.what();
        state.finished = utc_timestamp();
        folder.write_state(job, state);
        account(job, index, state);
    }
}

void JobLoop::finish_job(pid_t pid, int status) {
    auto it = running.find(pid);
    if (it == running.end()) return;
    RunningJob r = std::move(it->second);
    running.erase(it);
    const BatchJob& job = folder.jobs()[r.index];
    const int exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    const int signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    r.state.seconds = std::chrono::duration<double>(Clock::now() - r.start).count();
    r.state.seconds_total += r.state.seconds;
    r.state.finished = utc_timestamp();
    r.state.pid = 0;
    collect_job_result(folder,
                       job,
                       exit_code,
                       signal,
                       r.timed_out,
                       read_from(folder.log_path(job), r.log_offset),
                       r.state);
    folder.write_state(job, r.state);
    account(job, r.index, r.state);
}

// --timeout: SIGTERM at the limit, SIGKILL after the grace; returns the next such moment.
Clock::time_point JobLoop::enforce_timeouts() {
    Clock::time_point next = Clock::time_point::max();
    if (plan.timeout_seconds <= 0) return next;
    const Clock::time_point now = Clock::now();
    for (auto& [pid, r] : running) {
        const Clock::time_point term = r.start + seconds(plan.timeout_seconds);
        const Clock::time_point kill_at = term + seconds(kTimeoutGraceSeconds);
        if (!r.timed_out && now >= term) {
            r.timed_out = true;
            log_warning("{} ran past --timeout {:.0f} s: SIGTERM",
                        folder.jobs()[r.index].name,
                        plan.timeout_seconds);
            kill(-pid, SIGTERM);
        }
        if (r.timed_out && now >= kill_at) kill(-pid, SIGKILL);
        next = std::min(next, r.timed_out ? kill_at : term);
    }
    return next;
}

// Starts jobs up to --parallel and waits for children, timeouts and stop signals until none runs.
void JobLoop::run(const sigset_t& waited) {
    const int parallel = std::max(1, plan.parallel);
    while (true) {
        while (!outcome.stopped && !outcome.capped && running.size() < std::size_t(parallel) &&
               !queue.empty()) {
            const std::size_t index = queue.front();
            queue.pop_front();
            start_job(index);
        }
        if (running.empty()) break;
        const Clock::time_point next = enforce_timeouts();
        siginfo_t info;
        int s;
        if (next == Clock::time_point::max()) {
            s = sigwaitinfo(&waited, &info);
        } else {
            const auto wait = std::max(Clock::duration::zero(), next - Clock::now());
            const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(wait).count() + 1000000;
            const timespec limit{time_t(ns / 1000000000), long(ns % 1000000000)};
            s = sigtimedwait(&waited, &info, &limit);
        }
        if (s < 0) continue;  // EINTR, or a timeout came due (enforced above)
        if (s == SIGCHLD) {
            int status = 0;
            pid_t pid;
            while ((pid = waitpid(-1, &status, WNOHANG)) > 0) finish_job(pid, status);
        } else {
            if (!outcome.stopped)
                log_info("{} received: passing SIGTERM to {} running job(s) and starting no new one",
                         signal_name(s),
                         running.size());
            outcome.stopped = true;
            for (const auto& [pid, r] : running) kill(-pid, SIGTERM);
        }
    }
}

}  // namespace

JobRunOutcome run_jobs(const BatchFolder& folder, const JobRunPlan& plan) {
    sigset_t waited, previous;
    sigemptyset(&waited);
    for (int s : {SIGCHLD, SIGTERM, SIGINT, SIGUSR1}) sigaddset(&waited, s);
    sigprocmask(SIG_BLOCK, &waited, &previous);
    JobLoop loop(folder, plan);
    loop.run(waited);
    loop.outcome.not_started += int(loop.queue.size());
    sigprocmask(SIG_SETMASK, &previous, nullptr);
    return loop.outcome;
}

}  // namespace tdf
