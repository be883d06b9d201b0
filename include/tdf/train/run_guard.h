#pragma once
/// What keeps a run's output folder consistent under schedulers, retries and concurrency
/// (docs/commands/optimize.md "Runs that survive"): a refusal of dangerous output names, an
/// exclusive lock of the output folder, stop signals that end a run at the next iteration
/// boundary with a checkpoint, content hashes of every input (so a resume with changed inputs is
/// refused), the removal of temporaries a killed run left behind, and a completion record
/// written last.
#include <tdf/core/config.h>
#include <tdf/core/error.h>

#include <chrono>
#include <string>
#include <vector>

namespace tdf {

struct SceneDescription;

/// Exit code of a run stopped by SIGTERM, SIGINT or SIGUSR1 after it wrote its checkpoint:
/// nothing is lost, `--resume` continues it (sysexits' EX_TEMPFAIL: "try again").
constexpr int kExitInterrupted = 75;

/// Thrown by a run that stopped on a stop signal; its message says where the checkpoint is.
/// main() prints it as one line and exits with kExitInterrupted.
class RunInterrupted : public Error {
public:
    using Error::Error;
};

// ---- output names -------------------------------------------------------------------------

/// Refuses an empty output folder (`-o ''` would write into the file system's root) and a
/// file-name prefix that is empty, "." or "..", or contains a path separator (`--name ../x`
/// would write outside the output folder). Throws tdf::Error naming the option.
void validate_output_target(const std::string& output_dir, const std::string& name);

// ---- stop signals -------------------------------------------------------------------------

/// While an instance lives, SIGTERM, SIGINT and SIGUSR1 do not kill the process: the first one
/// sets a flag (and prints one line saying the run stops at the next iteration boundary) that
/// the iteration loop polls with stop_requested(). A second SIGINT (Ctrl-C twice) kills the
/// process as usual. The destructor restores the previous handlers. Not nestable.
class StopSignals {
public:
    StopSignals();
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;
};

/// True once a stop signal arrived (async-signal-safe flag).
bool stop_requested();
/// The first stop signal received, 0 when none.
int stop_signal();
/// Forgets a received signal (tests, and a batch runner that handled it).
void clear_stop_request();
/// "SIGTERM", "SIGINT", "SIGUSR1", or "signal N".
std::string signal_name(int signal);

/// Throws RunInterrupted saying which signal stopped the run after `iteration` and that the
/// checkpoint at `checkpoint_path` continues it with `--resume`.
[[noreturn]] void throw_interrupted(int iteration, const std::string& checkpoint_path);

// ---- output folder lock -------------------------------------------------------------------

/// An exclusive advisory lock (flock) on `<folder>/.tdf.lock`, held while the object lives and
/// released by the kernel when the process dies, however it dies. The lock file records the
/// holder (host, pid, command) for the refusal message. Creates the folder.
class OutputFolderLock {
public:
    /// Throws tdf::Error "output folder 'F' is in use by another tdf run (...)" when another
    /// process holds it. `command` names this run in the lock file ("optimize", "render").
    OutputFolderLock(const std::string& folder, const std::string& command);
    ~OutputFolderLock();
    OutputFolderLock(const OutputFolderLock&) = delete;
    OutputFolderLock& operator=(const OutputFolderLock&) = delete;

private:
    int m_fd = -1;
};

/// The lock file's name inside a locked folder.
constexpr const char* kLockFileName = ".tdf.lock";

// ---- temporaries --------------------------------------------------------------------------

/// True for names write_atomically() uses for its temporaries: `<stem>.tmp<pid>_<n>[.ext]`.
bool is_atomic_temporary(const std::string& file_name);

/// Removes, under `folder` (recursively), every temporary a killed run left behind. Only call
/// it while holding the folder's OutputFolderLock (no live run writes there then). Returns the
/// removed paths.
std::vector<std::string> remove_stale_temporaries(const std::string& folder);

// ---- input hashes -------------------------------------------------------------------------

/// Every file a scene reads: the scene file and its `parent` chain, the mesh and what it
/// references (OBJ `mtllib` and the MTL's maps, glTF external buffers and images), the albedo
/// image, the tactile maps and the label map; plus `extra` files (e.g. guidance exemplars).
/// Sorted, without duplicates, as given (absolute when the scene resolved them so).
std::vector<std::string> scene_input_files(const SceneDescription& scene,
                                           const std::vector<std::string>& extra = {});

/// Files named by `exemplars` arrays in a guidance configuration (`{"<backend>": {"exemplars": [...]}}`).
std::vector<std::string> guidance_exemplar_files(const Json& guidance_config);

/// {"<path>": "<16 hex digits>"} for each file.
Json hash_input_files(const std::vector<std::string>& paths);

/// "" when `current` equals `recorded`, else one line naming the changed, added and removed
/// inputs ("sphere.obj changed, albedo.png changed").
std::string describe_input_changes(const Json& recorded, const Json& current);

/// For `--resume`: throws tdf::Error before anything is written when the checkpoint at
/// `checkpoint_path` was made with another configuration (naming the first differing keys) or
/// other input contents (naming the files). `resolved_config` is the run's resolved
/// configuration as compact JSON text, `inputs` its hash_input_files(). A checkpoint without
/// recorded hashes (older tdf) is accepted with a warning.
void verify_resume(const std::string& checkpoint_path, const std::string& resolved_config,
                   const Json& inputs);

// ---- completion record --------------------------------------------------------------------

/// `<folder>/<name>_complete.json`: written last by a run that finished, so that a batch (or a
/// user) can tell a complete output set from one a killed run left. Contents: `command`,
/// `name`, `seconds`, `finished` (UTC, ISO 8601), `files` (every file under the folder except
/// the lock, the record and temporaries: relative `path`, `bytes`, `fnv1a`), plus `extra`'s keys.
std::string completion_record_path(const std::string& folder, const std::string& name);

/// What a run does first and last, in one object: the constructor validates the output names,
/// creates and locks the folder, removes stale temporaries (saying how many) and deletes an old
/// completion record (the folder is incomplete from now on); complete() writes the record.
class RunGuard {
public:
    RunGuard(const std::string& output_dir, const std::string& name, const std::string& command);
    /// Writes the completion record; `extra` keys are added to it (e.g. the report's path).
    void complete(const Json& extra = Json::object()) const;
    double seconds() const;

private:
    std::string m_folder, m_name, m_command;
    OutputFolderLock m_lock;
    std::chrono::steady_clock::time_point m_start;
};

/// Now, UTC, ISO 8601 (completion records, batch states).
std::string utc_timestamp();

}  // namespace tdf
