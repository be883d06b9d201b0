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
      m_start(std::chrono::steady_clock::now()),
      m_last(m_start) {}

void ProgressReporter::add_phase(std::size_t first_step, double relative_cost) {
    if (first_step == 0) {
        m_phases.front().cost = relative_cost;
        return;
    }
    m_phases.push_back(Phase{first_step, relative_cost, 0, 0.0});
}

void ProgressReporter::start_at(std::size_t n) {
    m_done = std::min(m_total, m_done + n);
    m_last = std::chrono::steady_clock::now();
}

std::size_t ProgressReporter::phase_of(std::size_t step) const {
    std::size_t k = 0;
    for (std::size_t i = 0; i < m_phases.size(); ++i)
        if (step >= m_phases[i].first) k = i;
    return k;
}

double ProgressReporter::eta_seconds() const {
    // Seconds per unit of cost from the most recently measured phase.
    double per_cost = 0;
    for (const Phase& p : m_phases)
        if (p.done > 0) per_cost = p.seconds / double(p.done) / p.cost;
    double eta = 0;
    for (std::size_t i = 0; i < m_phases.size(); ++i) {
        const Phase& p = m_phases[i];
        const std::size_t end = i + 1 < m_phases.size() ? m_phases[i + 1].first : m_total;
        const std::size_t begin = std::max(p.first, m_done);
        if (begin >= end) continue;
        const double rate = p.done > 0 ? p.seconds / double(p.done) : per_cost * p.cost;
        eta += double(end - begin) * rate;
    }
    return eta;
}

ProgressReporter::~ProgressReporter() { finish(); }

double ProgressReporter::elapsed_seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
}

void ProgressReporter::advance(std::size_t n, const std::string& status) {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - m_last).count();
    m_last = now;
    const std::size_t first = m_done;
    m_done = std::min(m_total, m_done + n);
    for (std::size_t step = first; step < m_done; ++step) {  // the time is spread over the steps
        Phase& p = m_phases[phase_of(step)];
        p.done += 1;
        p.seconds += seconds / double(m_done - first);
    }
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
    const double eta = eta_seconds();
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
