#include <signal.h>
#include <tdf/batch/batch_folder.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/exit_codes.h>
#include <tdf/guidance/subprocess.h>
#include <tdf/train/run_guard.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>
#include <filesystem>
#include <map>

namespace tdf {

namespace fs = std::filesystem;

const char* job_status_name(JobStatus status) {
    switch (status) {
        case JobStatus::Pending:
            return "pending";
        case JobStatus::Running:
            return "running";
        case JobStatus::Done:
            return "done";
        case JobStatus::Failed:
            return "failed";
        case JobStatus::Interrupted:
            return "interrupted";
    }
    return "pending";
}

const char* job_end_name(JobEnd end) {
    switch (end) {
        case JobEnd::None:
            return "";
        case JobEnd::Done:
            return "done";
        case JobEnd::FailedInput:
            return "failed-input";
        case JobEnd::FailedResource:
            return "failed-resource";
        case JobEnd::Preempted:
            return "preempted";
    }
    return "";
}

JobEnd classify_job_end(int exit_code, int signal, bool timed_out) {
    if (timed_out) return JobEnd::FailedResource;
    if (signal == SIGTERM || signal == SIGINT || signal == SIGUSR1 || exit_code == kExitInterrupted)
        return JobEnd::Preempted;
    // SIGKILL is what the kernel's (or a cgroup's) OOM killer sends; other signals are crashes
    // or a dying node. A crash that is deterministic costs --max-retries more tries, no more.
    if (signal != 0) return JobEnd::FailedResource;
    if (exit_code == kExitOutOfMemory || exit_code == kExitUnexpected) return JobEnd::FailedResource;
    return JobEnd::FailedInput;
}

JobStatus status_after(JobEnd end) {
    TDF_CHECK(end != JobEnd::None);  // pending or running: no attempt has ended
    switch (end) {
        case JobEnd::Done:
            return JobStatus::Done;
        case JobEnd::FailedInput:
        case JobEnd::FailedResource:
            return JobStatus::Failed;
        case JobEnd::Preempted:
            return JobStatus::Interrupted;
        case JobEnd::None:
            break;
    }
    return JobStatus::Failed;
}

namespace {
JobStatus parse_status(const std::string& s) {
    for (JobStatus status :
         {JobStatus::Pending, JobStatus::Running, JobStatus::Done, JobStatus::Failed, JobStatus::Interrupted})
        if (s == job_status_name(status)) return status;
    throw_error("unknown job status '{}'", s);
}
}  // namespace

Json JobState::to_json() const {
    return {{"status", job_status_name(status)},
            {"class", job_end_name(end)},
            {"exit_code", exit_code},
            {"signal", signal},
            {"error", error},
            {"attempts", attempts},
            {"tries", tries},
            {"seconds", seconds},
            {"seconds_total", seconds_total},
            {"started", started},
            {"finished", finished},
            {"host", host},
            {"failed_hosts", failed_hosts},
            {"pid", pid},
            {"slurm_job", slurm_job},
            {"requeued", requeued},
            {"command_line", command_line},
            {"output", output},
            {"thumbnail", thumbnail},
            {"quality", quality}};
}

JobState JobState::from_json(const Json& json) {
    JobState s;
    s.status = parse_status(json.value("status", std::string("pending")));
    s.exit_code = json.value("exit_code", -1);
    s.signal = json.value("signal", 0);
    s.error = json.value("error", std::string());
    s.attempts = json.value("attempts", 0);
    s.tries = json.value("tries", s.attempts);
    s.seconds = json.value("seconds", 0.0);
    s.seconds_total = json.value("seconds_total", 0.0);
    s.started = json.value("started", std::string());
    s.finished = json.value("finished", std::string());
    s.host = json.value("host", std::string());
    s.failed_hosts = json.value("failed_hosts", std::vector<std::string>());
    s.pid = json.value("pid", 0);
    s.slurm_job = json.value("slurm_job", std::string());
    s.requeued = json.value("requeued", false);
    s.command_line = json.value("command_line", std::string());
    s.output = json.value("output", std::string());
    s.thumbnail = json.value("thumbnail", std::string());
    if (json.contains("quality")) s.quality = json["quality"];
    const std::string end = json.value("class", std::string());
    for (JobEnd e : {JobEnd::Done, JobEnd::FailedInput, JobEnd::FailedResource, JobEnd::Preempted})
        if (end == job_end_name(e)) s.end = e;
    if (!end.empty() && s.end == JobEnd::None) throw_error("unknown job class '{}'", end);
    // States written before classes existed have none: derive it from how the job ended.
    if (!json.contains("class"))
        s.end = s.status == JobStatus::Done          ? JobEnd::Done
                : s.status == JobStatus::Interrupted ? JobEnd::Preempted
                : s.status == JobStatus::Failed      ? classify_job_end(s.exit_code, s.signal, false)
                                                     : JobEnd::None;
    return s;
}

std::string host_name() {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    return host;
}


BatchFolder BatchFolder::create(const std::string& root, const std::vector<BatchJob>& jobs,
                                const std::string& tdf_executable, const std::string& working_folder) {
    if (root.empty()) throw_error("-o/--output is empty: give the batch folder");
    BatchFolder folder;
    folder.m_root = fs::absolute(root).lexically_normal().string();
    while (folder.m_root.size() > 1 && folder.m_root.back() == '/') folder.m_root.pop_back();
    // Two jobs writing into one folder would refuse each other (the folder lock) or mix outputs.
    std::map<std::string, std::string> owner;
    for (const BatchJob& job : jobs) {
        const std::string out = folder.output_folder(job);
        if (out == folder.m_root || out == folder.path("state") || out == folder.path("logs"))
            throw_error(
                "job '{}': output folder '{}' is the batch folder or one of its own", job.name, job.output);
        const auto [it, fresh] = owner.emplace(out, job.name);
        if (!fresh)
            throw_error("jobs '{}' and '{}' have the same output folder '{}'", it->second, job.name, out);
    }
    const std::string manifest = folder.path("manifest.jsonl");
    if (fs::exists(manifest)) {
        const std::vector<BatchJob> recorded = read_manifest(manifest);
        const std::string changes = describe_manifest_changes(recorded, jobs);
        if (!changes.empty())
            throw_error(
                "batch folder '{}' was made from another manifest: {}; run the same manifest to continue it, "
                "or "
                "use another -o",
                root,
                changes);
        BatchFolder existing = open(root);
        return existing;
    }
    ensure_folder(folder.path("state"));
    ensure_folder(folder.path("logs"));
    folder.m_jobs = jobs;
    folder.m_tdf = tdf_executable;
    folder.m_working_folder = working_folder;
    write_text_atomically(folder.path("batch.json"),
                          Json({{"tdf", tdf_executable},
                                {"working_folder", working_folder},
                                {"created", utc_timestamp()},
                                {"jobs", jobs.size()}})
                                  .dump(2) +
                              "\n");
    // The manifest last: its presence marks a complete batch folder.
    write_text_atomically(manifest, manifest_to_jsonl(jobs));
    return folder;
}

BatchFolder BatchFolder::open(const std::string& root) {
    BatchFolder folder;
    folder.m_root = fs::absolute(root).lexically_normal().string();
    while (folder.m_root.size() > 1 && folder.m_root.back() == '/') folder.m_root.pop_back();
    const std::string manifest = folder.path("manifest.jsonl");
    if (!fs::exists(manifest))
        throw_error(
            "'{}' is not a batch folder (no manifest.jsonl; make one with `tdf batch run MANIFEST -o {}`)",
            root,
            root);
    folder.m_jobs = read_manifest(manifest);
    const Json settings = load_json_file(folder.path("batch.json"));
    folder.m_tdf = settings.value("tdf", std::string());
    folder.m_working_folder = settings.value("working_folder", std::string());
    return folder;
}

std::size_t BatchFolder::index_of(const std::string& name) const {
    for (std::size_t k = 0; k < m_jobs.size(); ++k)
        if (m_jobs[k].name == name) return k;
    throw_error("batch folder '{}' has no job '{}'", m_root, name);
}

std::string BatchFolder::path(const std::string& relative) const { return m_root + "/" + relative; }

std::string BatchFolder::output_folder(const BatchJob& job) const {
    if (job.output.empty()) return path("jobs/" + job.name);
    const fs::path out(job.output);
    std::string folder = (out.is_absolute() ? out : fs::path(m_root) / out).lexically_normal().string();
    while (folder.size() > 1 && folder.back() == '/') folder.pop_back();
    return folder;
}

std::string BatchFolder::state_path(const BatchJob& job) const { return path("state/" + job.name + ".json"); }
std::string BatchFolder::log_path(const BatchJob& job) const { return path("logs/" + job.name + ".log"); }

bool slurm_task_alive(const std::string& id, const std::string& scratch) {
    try {
        const std::string out = scratch + "/.squeue." + std::to_string(getpid()) + ".out";
        const std::string err = scratch + "/.squeue." + std::to_string(getpid()) + ".err";
        const ProcessOutcome outcome = run_process({"squeue", "-h", "-j", id, "-o", "%T"}, "", 30, out, err);
        const std::string listed = read_text_file(out), complaint = read_text_file(err);
        fs::remove(out);
        fs::remove(err);
        if (outcome.timed_out) return true;
        // Slurm answered "Invalid job id" (purged long ago) or listed nothing: gone. Any other
        // failure (controller unreachable) says nothing about the task.
        if (outcome.exit_code != 0) return complaint.find("Invalid job id") == std::string::npos;
        return listed.find_first_not_of(" \n") != std::string::npos;
    } catch (const Error&) {
        return true;  // no squeue here: cannot tell
    }
}

JobState BatchFolder::read_state(const BatchJob& job) const {
    const std::string file = state_path(job);
    if (!fs::exists(file)) return {};
    JobState state = JobState::from_json(load_json_file(file));
    if (state.status != JobStatus::Running) return state;
    const bool same_host_and_gone =
        state.host == host_name() && state.pid > 0 && kill(state.pid, 0) != 0 && errno == ESRCH;
    if (same_host_and_gone ||
        (!state.slurm_job.empty() && !slurm_task_alive(state.slurm_job, path("state")))) {
        // The runner itself was killed (OOM killer, node failure): not the job's input.
        state.end_attempt(JobEnd::FailedResource);
        state.tries += 1;  // the attempt ended, unrecorded
        state.failed_hosts.push_back(state.host);
        state.error = "the runner stopped without recording a result (killed?)";
    }
    return state;
}

void BatchFolder::write_state(const BatchJob& job, const JobState& state) const {
    write_text_atomically(state_path(job), state.to_json().dump(2) + "\n");
}

}  // namespace tdf
