#include <tdf/core/log.h>
#include <tdf/core/progress.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>

namespace tdf {

namespace {
std::atomic<LogLevel> g_level{LogLevel::Info};
std::mutex g_mutex;
bool g_bar_open = false;  // a progress bar owns the current terminal line

void close_bar_line() {
    if (g_bar_open) {
        std::fputc('\n', stderr);
        g_bar_open = false;
    }
}
}  // namespace

void set_log_level(LogLevel level) { g_level = level; }
LogLevel log_level() { return g_level; }

void log_line(const char* prefix, const std::string& message) {
    std::lock_guard<std::mutex> lock(g_mutex);
    close_bar_line();
    std::fprintf(stderr, "%s%s\n", prefix, message.c_str());
    std::fflush(stderr);
}

ProgressReporter::ProgressReporter(std::string title, std::size_t total, std::size_t line_every)
    : m_title(std::move(title)),
      m_total(std::max<std::size_t>(total, 1)),
      m_line_every(std::max<std::size_t>(line_every, 1)),
      m_tty(isatty(fileno(stderr)) != 0),
      m_start(std::chrono::steady_clock::now()) {}

ProgressReporter::~ProgressReporter() { finish(); }

double ProgressReporter::elapsed_seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
}

void ProgressReporter::advance(std::size_t n, const std::string& status) {
    m_done = std::min(m_total, m_done + n);
    if (!status.empty()) m_status = status;
    if (m_tty || m_done % m_line_every == 0 || m_done == m_total) draw(false);
}

void ProgressReporter::finish() {
    if (m_finished) return;
    m_finished = true;
    if (m_tty && log_level() > LogLevel::Quiet) {
        std::lock_guard<std::mutex> lock(g_mutex);
        close_bar_line();
    }
}

void ProgressReporter::draw(bool) {
    if (log_level() == LogLevel::Quiet) return;
    const double elapsed = elapsed_seconds();
    const double eta = m_done > 0 ? elapsed * double(m_total - m_done) / double(m_done) : 0.0;
    std::lock_guard<std::mutex> lock(g_mutex);
    if (m_tty) {
        constexpr int kWidth = 28;
        const int filled = int(double(kWidth) * double(m_done) / double(m_total));
        std::string bar(std::size_t(filled), '#');
        bar.resize(kWidth, '.');
        std::fprintf(stderr, "\r\033[K%s [%s] %zu/%zu %.1fs eta %.1fs %s", m_title.c_str(),
                     bar.c_str(), m_done, m_total, elapsed, eta, m_status.c_str());
        g_bar_open = true;
    } else {
        std::fprintf(stderr, "%s %zu/%zu %.1fs eta %.1fs %s\n", m_title.c_str(), m_done, m_total,
                     elapsed, eta, m_status.c_str());
    }
    std::fflush(stderr);
}

}  // namespace tdf
