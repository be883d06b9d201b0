#include <fmt/format.h>
#include <tdf/batch/batch_summary.h>

#include <tdf/report/batch_index.h>

#include <filesystem>
#include <tdf/core/atomic_file.h>

#include <set>

namespace tdf {

int BatchTotals::exit_code() const {
    if (failed > 0) return kBatchExitFailed;
    if (done == total()) return kBatchExitAllDone;
    return kBatchExitUnfinished;
}

BatchTotals batch_totals(const BatchFolder& folder) {
    BatchTotals t;
    for (const BatchJob& job : folder.jobs()) {
        const JobState state = folder.read_state(job);
        if (state.status == JobStatus::Failed)
            ++(state.end == JobEnd::FailedResource ? t.failed_resource : t.failed_input);
        switch (state.status) {
            case JobStatus::Pending:
                ++t.pending;
                break;
            case JobStatus::Running:
                ++t.running;
                break;
            case JobStatus::Done:
                ++t.done;
                break;
            case JobStatus::Failed:
                ++t.failed;
                break;
            case JobStatus::Interrupted:
                ++t.interrupted;
                break;
        }
    }
    return t;
}

namespace {

std::error_code& ec_ignore() {
    thread_local std::error_code ec;
    return ec;
}

std::string inside(const BatchFolder& folder, const std::string& path) {
    const std::string root = folder.root() + "/";
    return path.rfind(root, 0) == 0 ? path.substr(root.size()) : path;
}

std::string csv_field(const std::string& f) {
    if (f.find_first_of(",\"\n\r") == std::string::npos) return f;
    std::string out = "\"";
    for (char c : f) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

std::string csv_value(const Json& v) {
    if (v.is_null()) return "";
    if (v.is_string()) return csv_field(v.get<std::string>());
    if (v.is_number_float()) return fmt::format("{:.6g}", v.get<double>());
    return csv_field(v.dump());
}

}  // namespace

Json batch_summary_json(const BatchFolder& folder) {
    const BatchTotals t = batch_totals(folder);
    Json jobs = Json::array();
    for (const BatchJob& job : folder.jobs()) {
        const JobState s = folder.read_state(job);
        jobs.push_back({{"job", job.name},
                        {"command", job.command},
                        {"status", job_status_name(s.status)},
                        {"class", job_end_name(s.end)},
                        {"exit_code", s.exit_code},
                        {"signal", s.signal},
                        {"error", s.error},
                        {"attempts", s.attempts},
                        {"tries", s.tries},
                        {"seconds", s.seconds},
                        {"seconds_total", s.seconds_total},
                        {"started", s.started},
                        {"finished", s.finished},
                        {"host", s.host},
                        {"slurm_job", s.slurm_job},
                        {"output", inside(folder, folder.output_folder(job))},
                        {"log", inside(folder, folder.log_path(job))},
                        {"thumbnail", s.thumbnail},
                        {"quality", s.quality}});
    }
    return {{"batch", folder.root()},
            {"written", utc_timestamp()},
            {"totals",
             {{"jobs", t.total()},
              {"done", t.done},
              {"failed", t.failed},
              {"failed_input", t.failed_input},
              {"failed_resource", t.failed_resource},
              {"interrupted", t.interrupted},
              {"running", t.running},
              {"pending", t.pending}}},
            {"exit_code", t.exit_code()},
            {"jobs", jobs}};
}

void write_batch_summary(const BatchFolder& folder) {
    const Json summary = batch_summary_json(folder);
    write_text_atomically(folder.path("summary.json"), summary.dump(2) + "\n");
    std::set<std::string> quality_keys;
    for (const Json& job : summary["jobs"])
        for (auto it = job["quality"].begin(); it != job["quality"].end(); ++it)
            quality_keys.insert(it.key());
    const std::vector<std::string> columns = {"job",
                                              "command",
                                              "status",
                                              "class",
                                              "exit_code",
                                              "signal",
                                              "error",
                                              "attempts",
                                              "tries",
                                              "seconds",
                                              "seconds_total",
                                              "started",
                                              "finished",
                                              "host",
                                              "slurm_job",
                                              "output",
                                              "log",
                                              "thumbnail"};
    std::string csv;
    for (const std::string& c : columns) csv += (csv.empty() ? "" : ",") + c;
    for (const std::string& k : quality_keys) csv += ",quality." + k;
    csv += "\n";
    for (const Json& job : summary["jobs"]) {
        std::string row;
        for (std::size_t k = 0; k < columns.size(); ++k) row += (k ? "," : "") + csv_value(job[columns[k]]);
        for (const std::string& key : quality_keys)
            row += "," + (job["quality"].contains(key) ? csv_value(job["quality"][key]) : std::string());
        csv += row + "\n";
    }
    write_text_atomically(folder.path("summary.csv"), csv);

    // index.html: the same rows as a page (issue 16), each linking the job's own report page.
    std::vector<BatchRow> rows;
    for (const Json& job : summary["jobs"]) {
        BatchRow row;
        row.job = job["job"].get<std::string>();
        row.status = job["status"].get<std::string>();
        row.error = job["error"].get<std::string>();
        row.wall_seconds = job["seconds"].is_number() ? job["seconds"].get<double>() : -1.0;
        for (auto it = job["quality"].begin(); it != job["quality"].end(); ++it)
            if (it->is_number()) row.quality.emplace_back(it.key(), it->get<double>());
        const std::string out = job["output"].get<std::string>();
        for (const auto& entry : std::filesystem::directory_iterator(folder.path(out), ec_ignore()))
            if (entry.path().filename().string().size() > 12 &&
                entry.path().filename().string().rfind("_report.html") ==
                    entry.path().filename().string().size() - 12)
                row.page = entry.path().string();
        const std::string thumbnail = job["thumbnail"].get<std::string>();
        if (!thumbnail.empty() && std::filesystem::exists(folder.path(thumbnail))) row.thumbnail = folder.path(thumbnail);
        rows.push_back(std::move(row));
    }
    write_batch_index(folder.path("index.html"), "tdf batch " + folder.root(), rows);
}

std::string batch_status_table(const BatchFolder& folder) {
    std::string out;
    std::size_t width = 4;
    for (const BatchJob& job : folder.jobs()) width = std::max(width, job.name.size());
    const char* row = "{:<{}}  {:<11}  {:<15}  {:>9}  {:>8}  {:>5}  {}\n";
    out += fmt::format(
        fmt::runtime(row), "job", width, "status", "class", "seconds", "attempts", "tries", "error / output");
    for (const BatchJob& job : folder.jobs()) {
        const JobState s = folder.read_state(job);
        const std::string detail =
            s.status == JobStatus::Failed || s.status == JobStatus::Interrupted ? s.error
            : s.status == JobStatus::Pending                                    ? std::string()
                                             : inside(folder, folder.output_folder(job));
        out += fmt::format(fmt::runtime(row),
                           job.name,
                           width,
                           job_status_name(s.status),
                           s.end == JobEnd::None ? "-" : job_end_name(s.end),
                           fmt::format("{:.1f}", s.seconds_total),
                           s.attempts,
                           s.tries,
                           detail);
    }
    const BatchTotals t = batch_totals(folder);
    out += fmt::format(
        "{} jobs: {} done, {} failed, {} interrupted, {} running, {} pending ({} failed-input, "
        "{} failed-resource)\n",
        t.total(),
        t.done,
        t.failed,
        t.interrupted,
        t.running,
        t.pending,
        t.failed_input,
        t.failed_resource);
    return out;
}

}  // namespace tdf
