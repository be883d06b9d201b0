#include <tdf/train/loss_log.h>

#include <tdf/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace tdf {

void LossLog::truncate(int iteration) {
    m_records.erase(std::remove_if(m_records.begin(), m_records.end(),
                                   [&](const LossRecord& r) { return r.iteration >= iteration; }),
                    m_records.end());
}

std::string LossLog::to_json_lines() const {
    std::string out;
    for (const LossRecord& r : m_records) {
        Json line = {{"iteration", r.iteration}, {"seconds", r.seconds}};
        for (const auto& [name, value] : r.terms) line[name] = value;
        out += line.dump() + "\n";
    }
    return out;
}

LossLog LossLog::from_json_lines(const std::string& text, const std::string& source) {
    LossLog log;
    std::istringstream in(text);
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
        ++number;
        if (line.empty()) continue;
        const Json j = parse_json(line, fmt::format("{}:{}", source, number));
        LossRecord r;
        if (!j.is_object() || !j.contains("iteration")) throw_error("{}:{}: not a loss record", source, number);
        for (auto it = j.begin(); it != j.end(); ++it) {
            if (!it->is_number()) throw_error("{}:{}: '{}' is not a number", source, number, it.key());
            if (it.key() == "iteration")
                r.iteration = it->get<int>();
            else if (it.key() == "seconds")
                r.seconds = it->get<double>();
            else
                r.terms[it.key()] = it->get<double>();
        }
        log.add(std::move(r));
    }
    return log;
}

std::string LossLog::to_svg(int init_iterations) const {
    constexpr double kWidth = 800, kHeight = 480, kLeft = 70, kRight = 190, kTop = 20, kBottom = 50;
    std::set<std::string> names;
    double lo = 1e300, hi = -1e300;
    int last_iteration = 1;
    for (const LossRecord& r : m_records) {
        last_iteration = std::max(last_iteration, r.iteration);
        for (const auto& [name, value] : r.terms) {
            names.insert(name);
            if (value > 0 && std::isfinite(value)) {
                lo = std::min(lo, value);
                hi = std::max(hi, value);
            }
        }
    }
    if (lo > hi) lo = 1e-3, hi = 1;
    const double log_lo = std::floor(std::log10(lo)), log_hi = std::max(std::ceil(std::log10(hi)), log_lo + 1);
    const double plot_w = kWidth - kLeft - kRight, plot_h = kHeight - kTop - kBottom;
    const auto x_of = [&](double it) { return kLeft + plot_w * it / double(last_iteration); };
    const auto y_of = [&](double v) {
        return kTop + plot_h * (1.0 - (std::log10(std::max(v, lo)) - log_lo) / (log_hi - log_lo));
    };
    static const char* kColors[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
    std::string svg = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" font-family=\"sans-serif\" "
        "font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
        kWidth, kHeight);
    for (double e = log_lo; e <= log_hi; e += 1) {
        const double y = y_of(std::pow(10.0, e));
        svg += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#ddd\"/>"
                           "<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">1e{}</text>\n",
                           kLeft, y, kLeft + plot_w, y, kLeft - 6, y + 4, int(e));
    }
    svg += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#999\" "
                       "stroke-dasharray=\"4 3\"/><text x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\">"
                       "refinement starts</text>\n",
                       x_of(init_iterations), kTop, kTop + plot_h, kTop + plot_h + 30);
    svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">iteration (0 to {})</text>\n",
                       kLeft + plot_w / 2, kHeight - 6, last_iteration);
    int index = 0;
    for (const std::string& name : names) {
        const char* color = kColors[index % 10];
        std::string points;
        for (const LossRecord& r : m_records) {
            const auto it = r.terms.find(name);
            if (it == r.terms.end() || !(it->second > 0)) continue;
            points += fmt::format("{:.1f},{:.1f} ", x_of(r.iteration), y_of(it->second));
        }
        svg += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n", color,
                           points);
        const double ly = kTop + 16.0 * index + 10;
        svg += fmt::format("<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"{3}\" stroke-width=\"3\"/>"
                           "<text x=\"{4}\" y=\"{5}\">{6}</text>\n",
                           kWidth - kRight + 10, ly, kWidth - kRight + 30, color, kWidth - kRight + 36, ly + 4,
                           name);
        ++index;
    }
    svg += "</svg>\n";
    return svg;
}

}  // namespace tdf
