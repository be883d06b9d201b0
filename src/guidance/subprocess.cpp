#include <tdf/guidance/subprocess.h>

#include <tdf/core/error.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

namespace tdf {

namespace {
// The child reports an exec failure through a close-on-exec pipe: a successful exec closes it
// (the parent reads 0 bytes), a failure writes errno and the step that failed.
struct ChildFailure {
    int step;  // 0 chdir, 1 open stdout, 2 open stderr, 3 exec
    int error;
};

[[noreturn]] void child_fail(int fd, int step) {
    const ChildFailure failure{step, errno};
    ssize_t ignored = write(fd, &failure, sizeof failure);
    (void)ignored;
    _exit(127);
}

int open_output(const std::string& path, bool append) {
    return open(path.empty() ? "/dev/null" : path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (append ? O_APPEND : O_TRUNC),
                0644);
}
}  // namespace

int spawn_process(const std::vector<std::string>& argv, const std::string& working_folder,
                  const std::string& stdout_path, const std::string& stderr_path, bool append) {
    TDF_CHECK(!argv.empty());
    // Everything the child needs is prepared before fork: after fork in a multi-threaded process
    // only async-signal-safe calls are allowed until exec.
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);

    int report[2];
    if (pipe2(report, O_CLOEXEC) != 0)
        throw_error("cannot run '{}': pipe: {}", argv[0], std::strerror(errno));

    sigset_t no_signals;
    sigemptyset(&no_signals);
    const pid_t pid = fork();
    if (pid < 0) {
        close(report[0]);
        close(report[1]);
        throw_error("cannot run '{}': fork: {}", argv[0], std::strerror(errno));
    }
    if (pid == 0) {
        // Own process group, so a timeout kills the program and everything it started.
        setpgid(0, 0);
        // A caller waiting with sigwaitinfo blocks signals; the program must not inherit that.
        sigprocmask(SIG_SETMASK, &no_signals, nullptr);
        if (!working_folder.empty() && chdir(working_folder.c_str()) != 0) child_fail(report[1], 0);
        const int out = open_output(stdout_path, append);
        if (out < 0) child_fail(report[1], 1);
        const int err = open_output(stderr_path, append);
        if (err < 0) child_fail(report[1], 2);
        dup2(out, STDOUT_FILENO);
        dup2(err, STDERR_FILENO);
        const int null_in = open("/dev/null", O_RDONLY | O_CLOEXEC);
        if (null_in >= 0) dup2(null_in, STDIN_FILENO);
        execvp(args[0], args.data());
        child_fail(report[1], 3);
    }
    // Also set the group from the parent: whichever runs first wins, and the kill below must not
    // race with the child's own setpgid.
    setpgid(pid, pid);
    close(report[1]);
    ChildFailure failure{};
    ssize_t got;
    do {
        got = read(report[0], &failure, sizeof failure);
    } while (got < 0 && errno == EINTR);
    close(report[0]);
    if (got == ssize_t(sizeof failure)) {
        int ignored;
        waitpid(pid, &ignored, 0);
        switch (failure.step) {
            case 0:
                throw_error("cannot run '{}': cannot enter folder '{}': {}",
                            argv[0],
                            working_folder,
                            std::strerror(failure.error));
            case 1:
                throw_error("cannot run '{}': cannot create '{}': {}",
                            argv[0],
                            stdout_path,
                            std::strerror(failure.error));
            case 2:
                throw_error("cannot run '{}': cannot create '{}': {}",
                            argv[0],
                            stderr_path,
                            std::strerror(failure.error));
            default:
                throw_error("cannot run '{}': {}", argv[0], std::strerror(failure.error));
        }
    }
    return pid;
}

ProcessOutcome run_process(const std::vector<std::string>& argv, const std::string& working_folder,
                           double timeout_seconds, const std::string& stdout_path,
                           const std::string& stderr_path) {
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = spawn_process(argv, working_folder, stdout_path, stderr_path);

    ProcessOutcome outcome;
    const auto deadline = start + std::chrono::duration<double>(timeout_seconds);
    int status = 0;
    // Poll with a short back-off: waitpid has no timeout, and a SIGCHLD handler would interfere
    // with the host program's own signal handling.
    auto pause = std::chrono::milliseconds(1);
    while (true) {
        const pid_t done = waitpid(pid, &status, WNOHANG);
        if (done == pid) break;
        if (done < 0 && errno != EINTR)
            throw_error("waiting for '{}' failed: {}", argv[0], std::strerror(errno));
        if (std::chrono::steady_clock::now() >= deadline) {
            kill(-pid, SIGKILL);
            while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
            }
            outcome.timed_out = true;
            break;
        }
        std::this_thread::sleep_for(pause);
        pause = std::min(pause * 2, std::chrono::milliseconds(50));
    }
    outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (WIFEXITED(status)) outcome.exit_code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
    return outcome;
}

std::string file_tail(const std::string& path, int max_lines) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    const std::streamoff start = std::max<std::streamoff>(0, size - 4096);
    in.seekg(start);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    // Cut after the max_lines-th newline from the end.
    std::size_t cut = text.size();
    for (int lines = 0; lines < max_lines; ++lines) {
        const std::size_t newline = cut == 0 ? std::string::npos : text.rfind('\n', cut - 1);
        if (newline == std::string::npos) return text;
        cut = newline;
    }
    text = text.substr(cut + 1);
    return text;
}

std::string format_command(const std::vector<std::string>& argv) {
    std::string out;
    for (const std::string& a : argv) {
        if (!out.empty()) out += ' ';
        if (a.find_first_of(" \t'\"") == std::string::npos && !a.empty()) {
            out += a;
            continue;
        }
        out += '\'';
        for (char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
        out += '\'';
    }
    return out;
}

}  // namespace tdf
