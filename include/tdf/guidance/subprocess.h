#pragma once
/// Running a child program with a timeout, without a shell: fork, setpgid, chdir, redirect
/// stdout/stderr to files, execvp; the parent polls waitpid and kills the child's whole process
/// group with SIGKILL at the deadline (so helpers the program started die with it).
#include <string>
#include <vector>

namespace tdf {

struct ProcessOutcome {
    bool timed_out = false;  ///< killed at the deadline
    int exit_code = -1;      ///< exit status when it exited normally, else -1
    int signal = 0;          ///< terminating signal when killed (SIGKILL after a timeout), else 0
    double seconds = 0.0;    ///< wall-clock run time
};

/// Starts `argv` (argv[0] looked up in PATH) in its own process group, in `working_folder`, with
/// stdout and stderr going to the given files ("" = /dev/null; appended to when `append`, else
/// truncated), stdin from /dev/null and an empty signal mask; returns its pid without waiting.
/// Throws tdf::Error naming argv[0] when it cannot be started. The caller reaps it (waitpid).
int spawn_process(const std::vector<std::string>& argv, const std::string& working_folder,
                  const std::string& stdout_path, const std::string& stderr_path, bool append = false);

/// Runs `argv` (argv[0] looked up in PATH) in `working_folder` with stdout and stderr written to
/// the given files (created or truncated; "" = /dev/null). Waits at most `timeout_seconds`.
/// Throws tdf::Error naming argv[0] when the program cannot be started (not found, not
/// executable, fork failure). A non-zero exit is not an error here: see ProcessOutcome.
ProcessOutcome run_process(const std::vector<std::string>& argv, const std::string& working_folder,
                           double timeout_seconds, const std::string& stdout_path,
                           const std::string& stderr_path);

/// The last `max_lines` lines of a text file (at most 4 KiB), "" when unreadable; for messages.
std::string file_tail(const std::string& path, int max_lines = 5);

/// argv joined with spaces, arguments with spaces or quotes in single quotes; for messages.
std::string format_command(const std::vector<std::string>& argv);

}  // namespace tdf
