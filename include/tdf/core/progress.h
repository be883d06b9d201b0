#pragma once
/// Progress of long work. On a terminal: one self-updating bar with a status text and an ETA.
/// Elsewhere (logs, Slurm): a plain line every `line_every` steps and at the end. Silent when
/// the log level is Quiet.
#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

namespace tdf {

class ProgressReporter {
public:
    ProgressReporter(std::string title, std::size_t total, std::size_t line_every = 10);
    ~ProgressReporter();
    /// Steps from `first_step` on cost about `relative_cost` times the steps before them (a run's
    /// phases: a cheap matching phase, an expensive refinement). The ETA weighs the remaining steps
    /// of each phase by its measured seconds per step, or, for a phase not started yet, by the last
    /// measured phase's rate scaled by the ratio of the costs.
    void add_phase(std::size_t first_step, double relative_cost);
    /// Counts `n` steps as done before this process started (a resumed run): they move the bar
    /// but take no time, so they do not enter the rates.
    void start_at(std::size_t n);
    /// Marks `n` more steps done and sets the text shown after the bar (e.g. the losses).
    void advance(std::size_t n = 1, const std::string& status = {});
    /// Seconds still to go, as drawn.
    double eta_seconds() const;
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
    struct Phase {
        std::size_t first = 0;
        double cost = 1.0;
        std::size_t done = 0;  // steps of this phase done in this process
        double seconds = 0;    // time they took
    };
    std::vector<Phase> m_phases{Phase{}};
    std::chrono::steady_clock::time_point m_last;
    std::size_t phase_of(std::size_t step) const;
};

}  // namespace tdf
