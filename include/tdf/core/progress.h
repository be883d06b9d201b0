#pragma once
/// Progress of long work. On a terminal: one self-updating bar with a status text and an ETA.
/// Elsewhere (logs, Slurm): a plain line every `line_every` steps and at the end. Silent when
/// the log level is Quiet.
#include <chrono>
#include <cstddef>
#include <string>

namespace tdf {

class ProgressReporter {
public:
    ProgressReporter(std::string title, std::size_t total, std::size_t line_every = 10);
    ~ProgressReporter();
    /// Marks `n` more steps done and sets the text shown after the bar (e.g. the losses).
    void advance(std::size_t n = 1, const std::string& status = {});
    /// Ends the bar (also done by the destructor).
    void finish();
    double elapsed_seconds() const;

private:
    void draw(bool final_line);

    std::string m_title;
    std::size_t m_total;
    std::size_t m_done = 0;
    std::size_t m_line_every;
    std::string m_status;
    bool m_tty;
    bool m_finished = false;
    std::chrono::steady_clock::time_point m_start;
};

}  // namespace tdf
