#pragma once
/// Batch manifests (docs/commands/batch.md): a list of jobs, each one `tdf` subcommand with its
/// arguments, a job name and an output folder. Two spellings of the same content:
///
/// JSON lines (`.jsonl`, or any file whose first non-blank character is `{`), one job a line:
///   {"name": "spot_oak", "command": "optimize", "args": ["scenes/spot/scene.json", "seed=3"],
///    "output": "spot_oak"}
///   `args` is an array of strings, or one string split like a shell (whitespace; '...' and "..."
///   group). `output` is optional. Blank lines and lines starting with `#` are skipped.
///
/// CSV (RFC 4180: fields with commas, quotes or newlines in double quotes, `""` for a quote),
/// a header naming the columns `name`, `command`, `args` and optionally `output`, in any order:
///   name,command,args,output
///   spot_oak,optimize,scenes/spot/scene.json seed=3,spot_oak
///
/// Rules: names are 1-100 characters of [A-Za-z0-9._-], not starting with '.', and unique;
/// commands are optimize, render, compare, tactile or atlas. `{out}` in an argument stands for
/// the job's output folder (absolute). Relative `output` folders are inside the batch folder;
/// an empty one means `jobs/<name>`.
#include <tdf/core/config.h>

#include <string>
#include <vector>

namespace tdf {

struct BatchJob {
    std::string name;
    std::string command;            ///< optimize | render | compare | tactile | atlas
    std::vector<std::string> args;  ///< arguments after the subcommand
    std::string output;             ///< as written; "" = jobs/<name>
    std::string where;              ///< "manifest:line" of its row, for messages (not compared)

    Json to_json() const;
    bool operator==(const BatchJob& other) const;
};

/// The subcommands a batch job may run.
const std::vector<std::string>& batch_commands();

/// Reads a manifest file (format detected from its first non-blank character). Throws
/// tdf::Error with `path:line: problem` on any error, including an empty manifest, a duplicate
/// name, or an optimize/render `key=value` override that does not parse.
std::vector<BatchJob> read_manifest(const std::string& path);

/// Parses manifest text; `source` names it in messages.
std::vector<BatchJob> parse_manifest(const std::string& text, const std::string& source);

/// Throws tdf::Error (`path:line: job 'a': input file 'x.obj' does not exist`) for the first
/// job naming an input that is not there: an argument with an input file's extension (.json,
/// .obj, .gltf, .glb, .ply, .exr, .png, .jpg, .jpeg, .hdr, .tif, .tiff, .npz), relative to
/// `working_folder`, that is not an output (after -o/--output, or containing {out}); and absolute
/// such paths in `key=value` overrides (relative ones resolve against the scene's folder).
void check_job_inputs(const std::vector<BatchJob>& jobs, const std::string& working_folder);

/// Splits a shell-like argument string: whitespace separates, '...' and "..." group (no escapes
/// inside single quotes; \" and \\ inside double quotes). Throws on an unclosed quote.
std::vector<std::string> split_arguments(const std::string& text, const std::string& where);

/// The canonical JSON-lines form (what a batch folder keeps as manifest.jsonl).
std::string manifest_to_jsonl(const std::vector<BatchJob>& jobs);
/// The same jobs as CSV (header name,command,args,output; args joined with shell quoting).
std::string manifest_to_csv(const std::vector<BatchJob>& jobs);

/// "" when `current` lists the same jobs as `recorded` (same order, names, commands, arguments,
/// outputs); otherwise one line saying what changed ("job 'a': args differ (...); job 'c' added").
std::string describe_manifest_changes(const std::vector<BatchJob>& recorded,
                                      const std::vector<BatchJob>& current);

}  // namespace tdf
