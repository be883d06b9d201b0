#pragma once
/// The per-iteration loss record of a run: every term already multiplied by its weight
/// (like the reference's loss dict, spec 8.1), written as JSON lines and plotted as SVG.
#include <tdf/core/config.h>

#include <map>
#include <string>
#include <vector>

namespace tdf {

struct LossRecord {
    int iteration = 0;
    std::map<std::string, double> terms;  ///< weighted values; "total" is their sum
    double seconds = 0;                   ///< wall time of this iteration
};

class LossLog {
public:
    void add(LossRecord record) { m_records.push_back(std::move(record)); }
    const std::vector<LossRecord>& records() const { return m_records; }
    /// Keeps only records with iteration < `iteration` (resume from a checkpoint).
    void truncate(int iteration);

    /// One JSON object per line: {"iteration": i, "seconds": s, "<term>": value, ...}.
    std::string to_json_lines() const;
    /// Parses what to_json_lines wrote; throws tdf::Error naming `source` on bad lines.
    static LossLog from_json_lines(const std::string& text, const std::string& source);
    /// A line plot of every term against the iteration (log-scale y), with a legend and
    /// the phase boundary marked at `init_iterations`.
    std::string to_svg(int init_iterations) const;

private:
    std::vector<LossRecord> m_records;
};

}  // namespace tdf
