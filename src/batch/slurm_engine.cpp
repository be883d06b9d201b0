#include <fmt/ranges.h>
#include <sys/stat.h>
#include <tdf/batch/job_runner.h>
#include <tdf/batch/slurm_engine.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/guidance/subprocess.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

namespace tdf {

namespace fs = std::filesystem;

namespace {

// Single quotes for the shell.
std::string shell_quote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

std::string first_line(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    const auto nl = text.find('\n');
    return nl == std::string::npos ? text : text.substr(0, nl);
}

// Runs sbatch; returns the job id it printed (--parsable: "id[;cluster]").
std::string sbatch(const SlurmOptions& options, const std::vector<std::string>& arguments,
                   const std::string& folder, int* exit_code_when_waiting) {
    std::vector<std::string> argv = {options.sbatch, "--parsable"};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    const std::string out = folder + "/sbatch.out", err = folder + "/sbatch.err";
    // --wait blocks until the job ends (Slurm polls, not us): no timeout then.
    const double timeout = exit_code_when_waiting ? 1e9 : 120;
    const ProcessOutcome outcome = run_process(argv, "", timeout, out, err);
    const std::string printed = first_line(read_text_file(out));
    if (exit_code_when_waiting) *exit_code_when_waiting = outcome.exit_code;
    if (printed.empty() || (outcome.exit_code != 0 && !exit_code_when_waiting))
        throw_error("sbatch failed (exit {}): {}",
                    outcome.exit_code,
                    first_line(file_tail(err, 3)).empty() ? format_command(argv) : file_tail(err, 3));
    return printed.substr(0, printed.find(';'));
}

void write_script(const std::string& path, const std::string& text) {
    write_text_atomically(path, text);
    chmod(path.c_str(), 0755);
}

}  // namespace

std::string slurm_array_spec(const std::vector<std::size_t>& indices, int max_parallel) {
    std::string spec;
    for (std::size_t k = 0; k < indices.size();) {
        std::size_t end = k;
        while (end + 1 < indices.size() && indices[end + 1] == indices[end] + 1) ++end;
        if (!spec.empty()) spec += ",";
        spec += end == k ? std::to_string(indices[k])
                         : std::to_string(indices[k]) + "-" + std::to_string(indices[end]);
        k = end + 1;
    }
    if (max_parallel > 0) spec += "%" + std::to_string(max_parallel);
    return spec;
}

Json SlurmOptions::to_json() const {
    return {{"max_parallel", max_parallel},
            {"cpus_per_task", cpus_per_task},
            {"signal_seconds", signal_seconds},
            {"sbatch_options", sbatch_options},
            {"sbatch", sbatch},
            {"max_array_size", max_array_size},
            {"max_retries", max_retries},
            {"retry_mem_factor", retry_mem_factor},
            {"retry_time_factor", retry_time_factor}};
}

SlurmOptions SlurmOptions::from_json(const Json& json) {
    SlurmOptions o;
    o.max_parallel = json.value("max_parallel", o.max_parallel);
    o.cpus_per_task = json.value("cpus_per_task", o.cpus_per_task);
    o.signal_seconds = json.value("signal_seconds", o.signal_seconds);
    o.sbatch_options = json.value("sbatch_options", o.sbatch_options);
    o.sbatch = json.value("sbatch", o.sbatch);
    o.max_array_size = json.value("max_array_size", o.max_array_size);
    o.max_retries = json.value("max_retries", o.max_retries);
    o.retry_mem_factor = json.value("retry_mem_factor", o.retry_mem_factor);
    o.retry_time_factor = json.value("retry_time_factor", o.retry_time_factor);
    return o;
}

int slurm_max_array_size() {
    constexpr int kSlurmDefault = 1001;
    try {
        const std::string out =
            fs::temp_directory_path().string() + "/tdf_scontrol_" + std::to_string(getpid()) + ".txt";
        const ProcessOutcome outcome = run_process({"scontrol", "show", "config"}, "", 60, out, "");
        const std::string text = read_text_file(out);
        fs::remove(out);
        const auto at = text.find("MaxArraySize");
        if (outcome.exit_code != 0 || at == std::string::npos) return kSlurmDefault;
        const auto eq = text.find('=', at);
        const int size = std::atoi(text.c_str() + eq + 1);
        return size > 0 ? size : kSlurmDefault;
    } catch (const Error&) {
        return kSlurmDefault;
    }
}

std::vector<std::pair<std::size_t, std::vector<std::size_t>>> split_array(
    const std::vector<std::size_t>& indices, int max_array_size) {
    const std::size_t size = std::size_t(std::max(1, max_array_size));
    std::vector<std::pair<std::size_t, std::vector<std::size_t>>> arrays;
    for (std::size_t index : indices) {
        const std::size_t base = index / size * size;
        if (arrays.empty() || arrays.back().first != base) arrays.push_back({base, {}});
        arrays.back().second.push_back(index - base);
    }
    return arrays;
}

std::string scale_sbatch_option(const std::string& option, double factor) {
    const auto ceil_of = [](double v) { return std::to_string((long long)std::ceil(v - 1e-9)); };
    if (option.rfind("--mem=", 0) == 0) {
        const std::string value = option.substr(6);
        char* end = nullptr;
        const double number = std::strtod(value.c_str(), &end);
        const std::string unit = end ? std::string(end) : std::string();
        double mb = number;  // Slurm's default unit
        if (unit == "K" || unit == "k")
            mb = number / 1024;
        else if (unit == "G" || unit == "g")
            mb = number * 1024;
        else if (unit == "T" || unit == "t")
            mb = number * 1024 * 1024;
        else if (!unit.empty() && unit != "M" && unit != "m")
            return option;  // not ours to read
        return "--mem=" + ceil_of(mb * factor);
    }
    if (option.rfind("--time=", 0) == 0) {
        // [D-]HH:MM:SS, [D-]HH:MM, [D-]HH, MM, MM:SS (Slurm's forms), in minutes.
        std::string value = option.substr(7);
        double days = 0;
        const auto dash = value.find('-');
        if (dash != std::string::npos) {
            days = std::atof(value.substr(0, dash).c_str());
            value = value.substr(dash + 1);
        }
        std::vector<double> parts;
        for (std::size_t start = 0;;) {
            const auto colon = value.find(':', start);
            parts.push_back(std::atof(value.substr(start, colon - start).c_str()));
            if (colon == std::string::npos) break;
            start = colon + 1;
        }
        double minutes = 0;
        if (dash != std::string::npos) {
            minutes =
                parts[0] * 60 + (parts.size() > 1 ? parts[1] : 0) + (parts.size() > 2 ? parts[2] / 60 : 0);
        } else if (parts.size() == 3) {
            minutes = parts[0] * 60 + parts[1] + parts[2] / 60;
        } else {
            minutes = parts[0] + (parts.size() > 1 ? parts[1] / 60 : 0);
        }
        return "--time=" + ceil_of((days * 24 * 60 + minutes) * factor);
    }
    return option;
}

std::string slurm_array_script(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                               const SlurmOptions& options, std::size_t base) {
    const std::string name = "tdf-" + fs::path(folder.root()).filename().string();
    std::string s = "#!/bin/bash\n";
    s += "# tdf batch: one array task per job of " + folder.root() +
         "/manifest.jsonl (docs/commands/batch.md).\n";
    s += "#SBATCH --job-name=" + name + "\n";
    s += "#SBATCH --array=" + slurm_array_spec(indices, options.max_parallel) + "\n";
    s += "#SBATCH --cpus-per-task=" + std::to_string(options.cpus_per_task) + "\n";
    s += "#SBATCH --ntasks=1\n";
    s += "#SBATCH --output=" + folder.root() + "/logs/slurm-%A_%a.out\n";
    s += "#SBATCH --open-mode=append\n";
    s += "#SBATCH --requeue\n";
    s += "#SBATCH --signal=B:USR1@" + std::to_string(options.signal_seconds) + "\n";
    s += "#SBATCH --chdir=" + folder.working_folder() + "\n";
    s += "# exec: the task runner is the batch shell, so --signal=B: reaches it directly.\n";
    const std::string task = base == 0 ? std::string("\"$SLURM_ARRAY_TASK_ID\"")
                                       : "\"$((" + std::to_string(base) + " + SLURM_ARRAY_TASK_ID))\"";
    if (base > 0)
        s += "# Task i runs job " + std::to_string(base) + " + i (the array was split at MaxArraySize).\n";
    s += "exec " + shell_quote(folder.tdf_executable()) + " batch task " + shell_quote(folder.root()) + " " +
         task + "\n";
    return s;
}

std::vector<SlurmJobGroup> slurm_job_groups(const BatchFolder& folder,
                                            const std::vector<std::size_t>& indices,
                                            const SlurmOptions& options) {
    std::map<std::pair<int, std::string>, std::vector<std::size_t>> groups;
    for (std::size_t k : indices) {
        const JobState s = folder.read_state(folder.jobs()[k]);
        const int tries = s.end == JobEnd::FailedResource ? s.tries : 0;
        std::map<std::string, int> failures;
        for (const std::string& host : s.failed_hosts) ++failures[host];
        std::string exclude;
        for (const auto& [host, n] : failures)
            if (n >= 2 && tries > 0) exclude += (exclude.empty() ? "" : ",") + host;
        groups[{tries, exclude}].push_back(k);
    }
    std::vector<SlurmJobGroup> out;
    for (const auto& [key, members] : groups) {
        const auto& [tries, exclude] = key;
        SlurmJobGroup group{members, {}};
        // After the originals: sbatch takes the last of a repeated option.
        for (const std::string& o : options.sbatch_options) {
            const bool mem = o.rfind("--mem=", 0) == 0, time = o.rfind("--time=", 0) == 0;
            if (tries > 0 && (mem || time))
                group.extra.push_back(scale_sbatch_option(
                    o, std::pow(mem ? options.retry_mem_factor : options.retry_time_factor, tries)));
        }
        if (!exclude.empty()) group.extra.push_back("--exclude=" + exclude);
        out.push_back(std::move(group));
    }
    return out;
}

SlurmSubmission submit_slurm(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                             const SlurmOptions& options) {
    if (indices.empty()) throw_error("nothing to submit: every job of '{}' is done", folder.root());
    const std::string dir = folder.path("slurm");
    ensure_folder(dir);
    ensure_folder(folder.path("logs"));
    write_text_atomically(dir + "/options.json", options.to_json().dump(2) + "\n");
    SlurmSubmission submission;
    const int max_array_size = options.max_array_size > 0 ? options.max_array_size : slurm_max_array_size();
    struct Array {
        std::size_t base;
        std::vector<std::size_t> tasks;
        std::vector<std::string> extra;
    };
    std::vector<Array> arrays;
    for (const SlurmJobGroup& group : slurm_job_groups(folder, indices, options))
        for (auto& [base, tasks] : split_array(group.indices, max_array_size))
            arrays.push_back({base, tasks, group.extra});
    if (arrays.size() > 1)
        log_info("{} jobs in {} arrays (MaxArraySize {}, retry groups); each starts after the one before",
                 indices.size(),
                 arrays.size(),
                 max_array_size);
    std::vector<std::string> specs;
    Json extras = Json::array();
    for (std::size_t a = 0; a < arrays.size(); ++a) {
        const Array& array = arrays[a];
        const std::string spec = slurm_array_spec(array.tasks, options.max_parallel);
        const std::string script =
            dir + (arrays.size() == 1 ? std::string("/array.sh") : "/array_" + std::to_string(a) + ".sh");
        write_script(script, slurm_array_script(folder, array.tasks, options, array.base));
        std::vector<std::string> array_args = options.sbatch_options;
        array_args.insert(array_args.end(), array.extra.begin(), array.extra.end());
        // One array after the other: %K then bounds the tasks of all of them together.
        if (!submission.array_jobs.empty())
            array_args.push_back("--dependency=afterany:" + submission.array_jobs.back());
        array_args.push_back(script);
        const std::string id = sbatch(options, array_args, dir, nullptr);
        log_info("submitted Slurm array job {} ({} tasks, --array={}{}{}{})",
                 id,
                 array.tasks.size(),
                 spec,
                 array.base > 0 ? ", job " + std::to_string(array.base) + " + task id" : std::string(),
                 array.extra.empty() ? "" : ", ",
                 fmt::format("{}", fmt::join(array.extra, " ")));
        submission.array_jobs.push_back(id);
        specs.push_back(spec);
        extras.push_back(array.extra);
    }
    submission.array_job = submission.array_jobs.front();
    submission.array_spec = specs.front();
    const std::string summary_script = dir + "/summary.sh";
    write_script(summary_script,
                 "#!/bin/bash\n# tdf batch: after every array task has ended: retries of resource failures, "
                 "else the summary.\nexec " +
                     shell_quote(folder.tdf_executable()) + " batch finish " + shell_quote(folder.root()) +
                     "\n");

    std::string after;
    for (const std::string& id : submission.array_jobs) after += ":" + id;
    std::vector<std::string> summary_args = options.sbatch_options;
    for (const std::string& a :
         std::vector<std::string>{"--job-name=tdf-summary",
                                  "--dependency=afterany" + after,
                                  "--kill-on-invalid-dep=no",
                                  "--cpus-per-task=1",
                                  "--ntasks=1",
                                  "--output=" + folder.root() + "/logs/slurm-summary-%j.out",
                                  "--chdir=" + folder.root()})
        summary_args.push_back(a);
    summary_args.push_back(summary_script);
    submission.summary_job = sbatch(options, summary_args, dir, nullptr);
    log_info("finish job {} runs after the array(s) (afterany)", submission.summary_job);
    {
        std::ofstream record(dir + "/submissions.jsonl", std::ios::app);
        record << Json({{"array_job", submission.array_job},
                        {"array_jobs", submission.array_jobs},
                        {"array", submission.array_spec},
                        {"arrays", specs},
                        {"extra_options", extras},
                        {"summary_job", submission.summary_job},
                        {"submitted", utc_timestamp()},
                        {"sbatch_options", options.sbatch_options}})
                      .dump()
               << "\n";
    }
    if (options.wait) {
        log_info("waiting for the arrays, their retry rounds and the summary (sbatch --wait)");
        // A finish job may submit a retry round with a finish job of its own: follow the chain.
        std::string waited;
        for (std::string next = submission.summary_job; next != waited; next = latest_finish_job(folder)) {
            wait_for_slurm_job(folder, options, next);
            waited = next;
        }
    }
    return submission;
}

std::string latest_finish_job(const BatchFolder& folder) {
    const std::string path = folder.path("slurm/submissions.jsonl");
    if (!fs::exists(path)) return {};
    const std::string text = read_text_file(path);
    std::string last;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        if (end > start) last = text.substr(start, end - start);
        start = end + 1;
    }
    if (last.empty()) return {};
    return parse_json(last, path).value("summary_job", std::string());
}

void wait_for_slurm_job(const BatchFolder& folder, const SlurmOptions& options, const std::string& id) {
    int exit_code = -1;
    std::vector<std::string> args = options.sbatch_options;  // partition, account: where it may run
    for (const std::string& a :
         std::vector<std::string>{"--job-name=tdf-wait",
                                  "--dependency=afterany:" + id,
                                  "--kill-on-invalid-dep=yes",  // a job purged already: nothing to wait for
                                  "--cpus-per-task=1",
                                  "--ntasks=1",
                                  "--output=/dev/null",
                                  "--wait",
                                  "--wrap=true"})
        args.push_back(a);
    sbatch(options, args, folder.path("slurm"), &exit_code);
}

int wait_for_requeued_jobs(const BatchFolder& folder, double max_seconds) {
    const auto start = std::chrono::steady_clock::now();
    std::string announced;
    for (;;) {
        std::vector<std::string> waiting;
        for (const BatchJob& job : folder.jobs()) {
            const JobState s = folder.read_state(job);  // a "running" task Slurm lost reads as failed
            if (s.slurm_job.empty()) continue;
            const bool rerun = s.status == JobStatus::Running ||
                               (s.status == JobStatus::Interrupted && s.requeued &&
                                slurm_task_alive(s.slurm_job, folder.path("state")));
            if (rerun) waiting.push_back(job.name + " (Slurm " + s.slurm_job + ")");
        }
        if (waiting.empty()) return 0;
        const std::string names = fmt::format("{}", fmt::join(waiting, ", "));
        const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (waited >= max_seconds) {
            log_warning("after {:.0f} s, still requeued or running: {}; summarising without them "
                        "(`tdf batch finish {}` summarises again once they end)",
                        waited,
                        names,
                        folder.root());
            return int(waiting.size());
        }
        if (names != announced) {
            log_info("waiting for requeued job(s) to run again before the summary: {}", names);
            announced = names;
        }
        std::this_thread::sleep_for(std::chrono::seconds(2));
    }
}

int submit_retry_round(const BatchFolder& folder) {
    const std::string path = folder.path("slurm/options.json");
    if (!fs::exists(path)) return 0;
    SlurmOptions options = SlurmOptions::from_json(load_json_file(path));
    options.wait = false;  // the finish job must end: `tdf batch run --wait` follows the rounds
    std::vector<std::size_t> retry;
    for (std::size_t k = 0; k < folder.jobs().size(); ++k) {
        const JobState s = folder.read_state(folder.jobs()[k]);
        if (s.status == JobStatus::Failed && !failed_for_good(s, options.max_retries)) retry.push_back(k);
    }
    if (retry.empty()) return 0;
    log_info("retry round: {} job(s) that failed for a resource and have tries left", retry.size());
    submit_slurm(folder, retry, options);
    return int(retry.size());
}

}  // namespace tdf
