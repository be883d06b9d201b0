#include <tdf/batch/manifest.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <set>

namespace tdf {

namespace {

void validate_job(const BatchJob& job, const std::string& where) {
    if (job.name.empty() || job.name.size() > 100 || job.name.front() == '.' ||
        job.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") !=
            std::string::npos)
        throw_error("{}: job name '{}' must be 1-100 characters of A-Z a-z 0-9 . _ - and not start with '.'",
                    where,
                    job.name);
    const auto& commands = batch_commands();
    if (std::find(commands.begin(), commands.end(), job.command) == commands.end())
        throw_error("{}: job '{}': unknown command '{}' (optimize, render, compare, tactile or atlas)",
                    where,
                    job.name,
                    job.command);
    if (job.args.empty()) throw_error("{}: job '{}' has no arguments", where, job.name);
    // optimize and render take scene overrides: one that does not parse would fail the job only
    // once it runs, after the batch had started.
    if (job.command == "optimize" || job.command == "render") {
        for (const std::string& a : job.args) {
            if (a.empty() || a.front() == '-' || a.find('=') == std::string::npos) continue;
            Json scratch = Json::object();
            try {
                apply_override(scratch, a);
            } catch (const Error& e) {
                throw_error("{}: job '{}': {}", where, job.name, e.what());
            }
        }
    }
}

bool has_input_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    static const std::set<std::string> kInputs = {".json",
                                                  ".obj",
                                                  ".gltf",
                                                  ".glb",
                                                  ".ply",
                                                  ".exr",
                                                  ".png",
                                                  ".jpg",
                                                  ".jpeg",
                                                  ".hdr",
                                                  ".tif",
                                                  ".tiff",
                                                  ".npz"};
    return kInputs.count(ext) > 0;
}

std::string quote_argument(const std::string& a) {
    if (!a.empty() && a.find_first_of(" \t\n'\"\\") == std::string::npos) return a;
    if (a.find('\'') == std::string::npos) return "'" + a + "'";
    std::string out = "\"";
    for (char c : a) {
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

std::string join_arguments(const std::vector<std::string>& args) {
    std::string out;
    for (const std::string& a : args) out += (out.empty() ? "" : " ") + quote_argument(a);
    return out;
}

// RFC 4180 records; `line` of each record's start for messages.
std::vector<std::pair<int, std::vector<std::string>>> parse_csv(const std::string& text,
                                                                const std::string& source) {
    std::vector<std::pair<int, std::vector<std::string>>> records;
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false, field_started = false;
    int line = 1, record_line = 1;
    const auto end_record = [&] {
        if (field_started || !fields.empty() || !field.empty()) {
            fields.push_back(field);
            bool blank = true;
            for (const auto& f : fields) blank = blank && f.find_first_not_of(" \t\r") == std::string::npos;
            if (!blank) records.push_back({record_line, fields});
        }
        fields.clear();
        field.clear();
        field_started = false;
    };
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (quoted) {
            if (c == '"') {
                if (i + 1 < text.size() && text[i + 1] == '"') {
                    field += '"';
                    ++i;
                } else {
                    quoted = false;
                }
            } else {
                if (c == '\n') ++line;
                field += c;
            }
            continue;
        }
        if (c == '"' && field.empty()) {
            quoted = true;
            field_started = true;
        } else if (c == ',') {
            fields.push_back(field);
            field.clear();
            field_started = true;
        } else if (c == '\n') {
            end_record();
            record_line = ++line;
        } else if (c != '\r') {
            field += c;
        }
    }
    if (quoted) throw_error("{}:{}: unclosed quote", source, record_line);
    end_record();
    return records;
}

std::vector<BatchJob> parse_csv_manifest(const std::string& text, const std::string& source) {
    const auto records = parse_csv(text, source);
    if (records.empty()) throw_error("{}: the manifest lists no jobs", source);
    std::map<std::string, std::size_t> column;
    for (std::size_t k = 0; k < records[0].second.size(); ++k) {
        std::string name = records[0].second[k];
        name.erase(0, name.find_first_not_of(" \t"));
        name.erase(name.find_last_not_of(" \t") + 1);
        if (name != "name" && name != "command" && name != "args" && name != "output")
            throw_error(
                "{}:1: unknown column '{}' (the header names name, command, args and optionally output)",
                source,
                name);
        column[name] = k;
    }
    for (const char* required : {"name", "command", "args"})
        if (!column.count(required))
            throw_error("{}:1: the header has no '{}' column (name,command,args[,output])", source, required);
    std::vector<BatchJob> jobs;
    for (std::size_t r = 1; r < records.size(); ++r) {
        const auto& [line, fields] = records[r];
        const std::string where = source + ":" + std::to_string(line);
        if (fields.size() != records[0].second.size())
            throw_error("{}: {} fields, the header has {}", where, fields.size(), records[0].second.size());
        BatchJob job;
        job.name = fields[column["name"]];
        job.command = fields[column["command"]];
        job.args = split_arguments(fields[column["args"]], where);
        if (column.count("output")) job.output = fields[column["output"]];
        job.where = where;
        validate_job(job, where);
        jobs.push_back(job);
    }
    return jobs;
}

std::vector<BatchJob> parse_jsonl_manifest(const std::string& text, const std::string& source) {
    std::vector<BatchJob> jobs;
    std::size_t start = 0;
    for (int line = 1; start < text.size(); ++line) {
        std::size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        const std::string row = text.substr(start, end - start);
        start = end + 1;
        const auto first = row.find_first_not_of(" \t\r");
        if (first == std::string::npos || row[first] == '#') continue;
        const std::string where = source + ":" + std::to_string(line);
        const Json json = parse_json(row, where);
        if (!json.is_object()) throw_error("{}: a job must be a JSON object", where);
        for (auto it = json.begin(); it != json.end(); ++it)
            if (it.key() != "name" && it.key() != "command" && it.key() != "args" && it.key() != "output")
                throw_error("{}: unknown key '{}' (name, command, args, output)", where, it.key());
        BatchJob job;
        const auto string_of = [&](const char* key, bool required) {
            if (!json.contains(key)) {
                if (required) throw_error("{}: missing \"{}\"", where, key);
                return std::string();
            }
            if (!json[key].is_string()) throw_error("{}: \"{}\" must be a string", where, key);
            return json[key].get<std::string>();
        };
        job.name = string_of("name", true);
        job.command = string_of("command", true);
        job.output = string_of("output", false);
        if (!json.contains("args")) throw_error("{}: missing \"args\"", where);
        if (json["args"].is_string()) {
            job.args = split_arguments(json["args"].get<std::string>(), where);
        } else if (json["args"].is_array()) {
            for (const Json& a : json["args"]) {
                if (!a.is_string()) throw_error("{}: \"args\" must hold strings", where);
                job.args.push_back(a.get<std::string>());
            }
        } else {
            throw_error("{}: \"args\" must be an array of strings or one string", where);
        }
        job.where = where;
        validate_job(job, where);
        jobs.push_back(job);
    }
    return jobs;
}

}  // namespace

void check_job_inputs(const std::vector<BatchJob>& jobs, const std::string& working_folder) {
    namespace fs = std::filesystem;
    for (const BatchJob& job : jobs) {
        for (std::size_t k = 0; k < job.args.size(); ++k) {
            const std::string& a = job.args[k];
            if (a.empty() || a.front() == '-' || a.find("{out}") != std::string::npos) continue;
            if (k > 0 && (job.args[k - 1] == "-o" || job.args[k - 1] == "--output")) continue;
            const auto eq = a.find('=');
            const std::string path = eq == std::string::npos ? a : a.substr(eq + 1);
            if (!has_input_extension(path) || (eq != std::string::npos && !fs::path(path).is_absolute()))
                continue;
            std::error_code ec;
            if (!fs::exists(fs::path(working_folder) / path, ec))
                throw_error("{}: job '{}': input file '{}' does not exist{}",
                            job.where,
                            job.name,
                            path,
                            fs::path(path).is_absolute() ? "" : " (relative to " + working_folder + ")");
        }
    }
}

Json BatchJob::to_json() const {
    Json json = {{"name", name}, {"command", command}, {"args", args}};
    if (!output.empty()) json["output"] = output;
    return json;
}

bool BatchJob::operator==(const BatchJob& other) const {
    return name == other.name && command == other.command && args == other.args && output == other.output;
}

const std::vector<std::string>& batch_commands() {
    static const std::vector<std::string> kCommands = {"optimize", "render", "compare", "tactile", "atlas"};
    return kCommands;
}

std::vector<std::string> split_arguments(const std::string& text, const std::string& where) {
    std::vector<std::string> out;
    std::string current;
    bool in_word = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (c == ' ' || c == '\t' || c == '\n' || c == '\r') {
            if (in_word) out.push_back(current);
            current.clear();
            in_word = false;
        } else if (c == '\'') {
            const std::size_t close = text.find('\'', i + 1);
            if (close == std::string::npos) throw_error("{}: unclosed ' in arguments: {}", where, text);
            current += text.substr(i + 1, close - i - 1);
            i = close;
            in_word = true;
        } else if (c == '"') {
            std::size_t j = i + 1;
            for (; j < text.size() && text[j] != '"'; ++j) {
                if (text[j] == '\\' && j + 1 < text.size() && (text[j + 1] == '"' || text[j + 1] == '\\'))
                    ++j;
                current += text[j];
            }
            if (j >= text.size()) throw_error("{}: unclosed \" in arguments: {}", where, text);
            i = j;
            in_word = true;
        } else {
            current += c;
            in_word = true;
        }
    }
    if (in_word) out.push_back(current);
    return out;
}

std::vector<BatchJob> parse_manifest(const std::string& text, const std::string& source) {
    const auto first = text.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) throw_error("{}: the manifest is empty", source);
    std::vector<BatchJob> jobs = text[first] == '{' || text[first] == '#' ? parse_jsonl_manifest(text, source)
                                                                          : parse_csv_manifest(text, source);
    if (jobs.empty()) throw_error("{}: the manifest lists no jobs", source);
    std::map<std::string, std::string> first_row;
    for (const BatchJob& job : jobs) {
        const auto [it, fresh] = first_row.emplace(job.name, job.where);
        if (!fresh)
            throw_error("{}: job name '{}' appears twice (first at {})", job.where, job.name, it->second);
    }
    return jobs;
}

std::vector<BatchJob> read_manifest(const std::string& path) {
    return parse_manifest(read_text_file(path), path);
}

std::string manifest_to_jsonl(const std::vector<BatchJob>& jobs) {
    std::string out;
    for (const BatchJob& job : jobs) out += job.to_json().dump() + "\n";
    return out;
}

std::string manifest_to_csv(const std::vector<BatchJob>& jobs) {
    const auto csv_field = [](const std::string& f) {
        if (f.find_first_of(",\"\n\r") == std::string::npos) return f;
        std::string out = "\"";
        for (char c : f) out += c == '"' ? std::string("\"\"") : std::string(1, c);
        return out + "\"";
    };
    std::string out = "name,command,args,output\n";
    for (const BatchJob& job : jobs)
        out += csv_field(job.name) + "," + csv_field(job.command) + "," +
               csv_field(join_arguments(job.args)) + "," + csv_field(job.output) + "\n";
    return out;
}

std::string describe_manifest_changes(const std::vector<BatchJob>& recorded,
                                      const std::vector<BatchJob>& current) {
    std::vector<std::string> changes;
    std::map<std::string, const BatchJob*> before, after;
    for (const BatchJob& j : recorded) before[j.name] = &j;
    for (const BatchJob& j : current) after[j.name] = &j;
    for (const BatchJob& j : recorded) {
        const auto it = after.find(j.name);
        if (it == after.end()) {
            changes.push_back("job '" + j.name + "' removed");
            continue;
        }
        const BatchJob& now = *it->second;
        if (now.command != j.command)
            changes.push_back("job '" + j.name + "': command " + j.command + " -> " + now.command);
        if (now.args != j.args)
            changes.push_back("job '" + j.name + "': args differ (was: " + join_arguments(j.args) +
                              "; now: " + join_arguments(now.args) + ")");
        if (now.output != j.output)
            changes.push_back("job '" + j.name + "': output '" + j.output + "' -> '" + now.output + "'");
    }
    for (const BatchJob& j : current)
        if (!before.count(j.name)) changes.push_back("job '" + j.name + "' added");
    if (changes.empty()) {
        // Same jobs: only the order can differ, and the order numbers the Slurm array tasks.
        for (std::size_t k = 0; k < recorded.size(); ++k)
            if (recorded[k].name != current[k].name) return "the jobs are in another order";
        return {};
    }
    std::string out;
    for (std::size_t k = 0; k < changes.size() && k < 6; ++k) out += (k ? "; " : "") + changes[k];
    if (changes.size() > 6) out += fmt::format("; and {} more", changes.size() - 6);
    return out;
}

}  // namespace tdf
