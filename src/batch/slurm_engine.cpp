#include <sys/stat.h>
#include <tdf/batch/slurm_engine.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/guidance/subprocess.h>

#include <filesystem>
#include <fstream>

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

std::string slurm_array_script(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                               const SlurmOptions& options) {
    const std::string name = "tdf-" + fs::path(folder.root()).filename().string();
    std::string s = "#!/bin/bash\n";
    s += "# tdf batch: one array task per job of " + folder.root() +
         "/manifest.jsonl (README \"tdf batch\").\n";
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
    s += "exec " + shell_quote(folder.tdf_executable()) + " batch task " + shell_quote(folder.root()) +
         " \"$SLURM_ARRAY_TASK_ID\"\n";
    return s;
}

SlurmSubmission submit_slurm(const BatchFolder& folder, const std::vector<std::size_t>& indices,
                             const SlurmOptions& options) {
    if (indices.empty()) throw_error("nothing to submit: every job of '{}' is done", folder.root());
    const std::string dir = folder.path("slurm");
    ensure_folder(dir);
    ensure_folder(folder.path("logs"));
    SlurmSubmission submission;
    submission.array_spec = slurm_array_spec(indices, options.max_parallel);
    const std::string array_script = dir + "/array.sh";
    write_script(array_script, slurm_array_script(folder, indices, options));
    const std::string summary_script = dir + "/summary.sh";
    write_script(summary_script,
                 "#!/bin/bash\n# tdf batch: the summary once every array task has ended.\nexec " +
                     shell_quote(folder.tdf_executable()) + " batch status " + shell_quote(folder.root()) +
                     " --summary\n");

    std::vector<std::string> array_args = options.sbatch_options;
    array_args.push_back(array_script);
    submission.array_job = sbatch(options, array_args, dir, nullptr);
    log_info("submitted Slurm array job {} ({} tasks, --array={})",
             submission.array_job,
             indices.size(),
             submission.array_spec);

    std::vector<std::string> summary_args = options.sbatch_options;
    for (const std::string& a :
         std::vector<std::string>{"--job-name=tdf-summary",
                                  "--dependency=afterany:" + submission.array_job,
                                  "--kill-on-invalid-dep=no",
                                  "--cpus-per-task=1",
                                  "--ntasks=1",
                                  "--output=" + folder.root() + "/logs/slurm-summary-%j.out",
                                  "--chdir=" + folder.root()})
        summary_args.push_back(a);
    if (options.wait) summary_args.push_back("--wait");
    summary_args.push_back(summary_script);
    // Record the array before waiting, so `tdf batch status` can name it meanwhile.
    {
        std::ofstream record(dir + "/submissions.jsonl", std::ios::app);
        record << Json({{"array_job", submission.array_job},
                        {"array", submission.array_spec},
                        {"submitted", utc_timestamp()},
                        {"sbatch_options", options.sbatch_options}})
                      .dump()
               << "\n";
    }
    if (options.wait) log_info("waiting for the array and the summary (sbatch --wait)");
    submission.summary_job =
        sbatch(options, summary_args, dir, options.wait ? &submission.summary_exit_code : nullptr);
    log_info("summary job {} runs after the array (afterany)", submission.summary_job);
    return submission;
}

}  // namespace tdf
