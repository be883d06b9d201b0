#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/texture_optimization.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace tdf {

namespace {

// Kwatra et al.'s robust exponent: weight = distance^((r - 2) / 2) on squared distances.
constexpr double kRobustPower = (0.8 - 2.0) / 2.0;
// Random candidates drawn from the whole source set per window and iteration (beyond
// PatchMatch's local search): they let windows escape a poor initial match.
constexpr int kFreshDraws = 2;

struct Source {
    int exemplar = 0, x = 0, y = 0;
};

// Summed-area table of a 1-channel image (w + 1) x (h + 1).
std::vector<double> summed_area(const Image& image, bool squared) {
    const int w = image.width(), h = image.height();
    std::vector<double> t(std::size_t(w + 1) * std::size_t(h + 1), 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double v = image.at(x, y, 0);
            t[std::size_t(y + 1) * std::size_t(w + 1) + std::size_t(x + 1)] =
                (squared ? v * v : v) + t[std::size_t(y) * std::size_t(w + 1) + std::size_t(x + 1)] +
                t[std::size_t(y + 1) * std::size_t(w + 1) + std::size_t(x)] -
                t[std::size_t(y) * std::size_t(w + 1) + std::size_t(x)];
        }
    return t;
}

double box_sum(const std::vector<double>& t, int width, int x, int y, int side) {
    const std::size_t stride = std::size_t(width + 1);
    return t[std::size_t(y + side) * stride + std::size_t(x + side)] - t[std::size_t(y) * stride + std::size_t(x + side)] -
           t[std::size_t(y + side) * stride + std::size_t(x)] + t[std::size_t(y) * stride + std::size_t(x)];
}

// The exemplar windows of one side that may be copied, per exemplar: allowed[y * px + x].
struct SourceSet {
    int side = 0;
    std::vector<int> positions_x, positions_y;
    std::vector<std::vector<std::uint8_t>> allowed;
    std::vector<std::vector<double>> means;  // window mean per position
    std::vector<Source> list;                // every allowed window, for uniform draws

    bool ok(const Source& s) const {
        const std::size_t e = std::size_t(s.exemplar);
        return s.x >= 0 && s.y >= 0 && s.x < positions_x[e] && s.y < positions_y[e] &&
               allowed[e][std::size_t(s.y) * std::size_t(positions_x[e]) + std::size_t(s.x)];
    }
    double mean(const Source& s) const {
        return means[std::size_t(s.exemplar)][std::size_t(s.y) * std::size_t(positions_x[std::size_t(s.exemplar)]) +
                                              std::size_t(s.x)];
    }
};

// Windows lying at least `min_coverage` in their region; when fewer than 64 (or 2 % of all)
// reach it, the bar drops to the coverage of the 64th best (as quilting's blocks do), so a
// thin region (rims, grooves) still gives its most covered windows.
SourceSet make_sources(const std::vector<Image>& exemplars, const std::vector<Image>& masks, int side,
                       float min_coverage) {
    SourceSet set;
    set.side = side;
    std::vector<std::vector<double>> coverage;
    std::vector<double> all;
    for (std::size_t i = 0; i < exemplars.size(); ++i) {
        const Image& e = exemplars[i];
        const int px = e.width() - side + 1, py = e.height() - side + 1;
        set.positions_x.push_back(px);
        set.positions_y.push_back(py);
        const std::vector<double> values = summed_area(e, false);
        const bool masked = i < masks.size() && !masks[i].empty();
        const std::vector<double> region = masked ? summed_area(masks[i], false) : std::vector<double>();
        std::vector<double> cover(std::size_t(px) * std::size_t(py), 1.0), mean(cover.size());
        const double n = double(side) * double(side);
        for (int y = 0; y < py; ++y)
            for (int x = 0; x < px; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(px) + std::size_t(x);
                mean[k] = box_sum(values, e.width(), x, y, side) / n;
                if (masked) cover[k] = box_sum(region, e.width(), x, y, side) / n;
            }
        all.insert(all.end(), cover.begin(), cover.end());
        coverage.push_back(std::move(cover));
        set.means.push_back(std::move(mean));
    }
    const std::size_t keep = std::min(all.size(), std::max<std::size_t>(64, all.size() / 50));
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(keep - 1), all.end(), std::greater<double>());
    const double needed = std::min(double(min_coverage), all[keep - 1]) - 1e-9;
    for (std::size_t i = 0; i < exemplars.size(); ++i) {
        std::vector<std::uint8_t> allowed(coverage[i].size());
        for (std::size_t k = 0; k < allowed.size(); ++k) {
            allowed[k] = coverage[i][k] >= needed;
            if (allowed[k])
                set.list.push_back({int(i), int(k % std::size_t(set.positions_x[i])), int(k / std::size_t(set.positions_x[i]))});
        }
        set.allowed.push_back(std::move(allowed));
    }
    TDF_CHECK(!set.list.empty());
    return set;
}

// Output windows on a grid: origins every `step` pixels along one axis.
std::vector<int> window_origins(int canvas, int side, int step, bool wrap) {
    std::vector<int> origins;
    if (wrap) {
        for (int o = 0; o < canvas; o += step) origins.push_back(o);
    } else {
        for (int o = 0; o + side < canvas; o += step) origins.push_back(o);
        origins.push_back(canvas - side);
    }
    return origins;
}

class Optimizer {
public:
    Optimizer(const std::vector<Image>& exemplars, const std::vector<Image>& masks, const Image& initial,
              const TextureOptimizationOptions& options)
        : m_exemplars(exemplars), m_masks(masks), m_options(options), m_out(initial) {}

    Image run() {
        std::uint64_t pass = 0;
        for (std::size_t k = 0; k < m_options.windows.size(); ++k) {
            const int side = m_options.windows[k];
            const int iterations = m_options.iterations[std::min(k, m_options.iterations.size() - 1)];
            if (side > m_out.width() || side > m_out.height()) continue;
            bool fits = true;
            for (const Image& e : m_exemplars) fits = fits && side <= e.width() && side <= e.height();
            if (!fits) continue;
            const SourceSet sources = make_sources(m_exemplars, m_masks, side, m_options.min_coverage);
            // The last side's final blend takes each pixel from one window. With windows every
            // side/4 px the source could change only between lines at the grid's step, so those
            // lines stepped more than the others (groove scan rows: odd/even 2.4x); windows at
            // every pixel leave no line pattern (+20-35 % CPU).
            const int step = side == m_options.windows.back() ? 1 : std::max(1, side / 4);
            m_xs = window_origins(m_out.width(), side, step, m_options.tileable);
            m_ys = window_origins(m_out.height(), side, step, m_options.tileable);
            m_matches.assign(m_xs.size() * m_ys.size(), Source{});
            m_distances.assign(m_matches.size(), 0.0);
            initial_matches(sources, pass);
            for (int i = 0; i < iterations; ++i) {
                if (i > 0) search(sources, ++pass);
                const bool last = k + 1 == m_options.windows.size() && i + 1 == iterations;
                blend(sources, last);
            }
            ++pass;
        }
        return m_out;
    }

private:
    int wrap_x(int x) const { return m_options.tileable ? (x % m_out.width() + m_out.width()) % m_out.width() : x; }
    int wrap_y(int y) const { return m_options.tileable ? (y % m_out.height() + m_out.height()) % m_out.height() : y; }

    // The output window at grid cell (i, j), mean removed, into `window`.
    void output_window(std::size_t i, std::size_t j, int side, std::vector<float>& window, double& mean) const {
        window.resize(std::size_t(side) * std::size_t(side));
        double sum = 0;
        for (int y = 0; y < side; ++y)
            for (int x = 0; x < side; ++x) {
                const float v = m_out.at(wrap_x(m_xs[i] + x), wrap_y(m_ys[j] + y), 0);
                window[std::size_t(y) * std::size_t(side) + std::size_t(x)] = v;
                sum += v;
            }
        mean = sum / double(window.size());
        for (float& v : window) v -= float(mean);
    }

    // Squared distance (mean removed) of `window` to source `s`, abandoned above `bound`.
    double distance(const SourceSet& sources, const std::vector<float>& window, const Source& s, double bound) const {
        const Image& e = m_exemplars[std::size_t(s.exemplar)];
        const float mean = float(sources.mean(s));
        const int side = sources.side;
        double d = 0;
        for (int y = 0; y < side; ++y) {
            const float* row = e.pixel(s.x, s.y + y);
            const float* w = &window[std::size_t(y) * std::size_t(side)];
            for (int x = 0; x < side; ++x) {
                const float diff = row[x] - mean - w[x];
                d += double(diff) * diff;
            }
            if (d > bound) return d;
        }
        return d;
    }

    void initial_matches(const SourceSet& sources, std::uint64_t pass) {
        // A full random start, improved by the search below: the first E step.
        parallel_for(m_matches.size(), 64, [&](std::size_t begin, std::size_t end) {
            std::vector<float> window;
            for (std::size_t q = begin; q < end; ++q) {
                Rng rng = Rng::stream(m_options.seed, pass * 0x100000000ULL + q);
                m_matches[q] = sources.list[std::size_t(rng.uniform_int(0, int(sources.list.size())))];
                double mean = 0;
                output_window(q % m_xs.size(), q / m_xs.size(), sources.side, window, mean);
                m_distances[q] = distance(sources, window, m_matches[q], std::numeric_limits<double>::infinity());
            }
        });
        for (int round = 0; round < 2; ++round) search(sources, pass * 16 + 1 + std::uint64_t(round));
    }

    // One PatchMatch round (E step), reading only the previous matches.
    void search(const SourceSet& sources, std::uint64_t pass) {
        const std::vector<Source> previous = m_matches;
        const std::size_t nx = m_xs.size(), ny = m_ys.size();
        const int side = sources.side;
        parallel_for(m_matches.size(), 64, [&](std::size_t begin, std::size_t end) {
            std::vector<float> window;
            for (std::size_t q = begin; q < end; ++q) {
                const std::size_t i = q % nx, j = q / nx;
                Rng rng = Rng::stream(m_options.seed, (pass + 1) * 0x100000000ULL + q);
                double mean = 0;
                output_window(i, j, side, window, mean);
                Source best = previous[q];
                double best_d = distance(sources, window, best, std::numeric_limits<double>::infinity());
                auto consider = [&](const Source& s) {
                    if (!sources.ok(s)) return;
                    const double d = distance(sources, window, s, best_d);
                    if (d < best_d) best_d = d, best = s;
                };
                // Neighbours' matches, shifted by the grid offset between the windows.
                auto neighbour = [&](std::size_t ni, std::size_t nj) {
                    const Source& n = previous[nj * nx + ni];
                    int dx = m_xs[i] - m_xs[ni], dy = m_ys[j] - m_ys[nj];
                    if (m_options.tileable) {  // the short way around the wrap
                        if (dx > m_out.width() / 2) dx -= m_out.width();
                        if (dx < -m_out.width() / 2) dx += m_out.width();
                        if (dy > m_out.height() / 2) dy -= m_out.height();
                        if (dy < -m_out.height() / 2) dy += m_out.height();
                    }
                    consider({n.exemplar, n.x + dx, n.y + dy});
                };
                const bool wrap = m_options.tileable;
                if (i > 0 || wrap) neighbour((i + nx - 1) % nx, j);
                if (i + 1 < nx || wrap) neighbour((i + 1) % nx, j);
                if (j > 0 || wrap) neighbour(i, (j + ny - 1) % ny);
                if (j + 1 < ny || wrap) neighbour(i, (j + 1) % ny);
                // Random search around the best, radius halving.
                const Image& e = m_exemplars[std::size_t(best.exemplar)];
                for (int r = std::max(e.width(), e.height()); r >= 1; r /= 2) {
                    const Source around = best;
                    consider({around.exemplar, around.x + rng.uniform_int(-r, r + 1), around.y + rng.uniform_int(-r, r + 1)});
                }
                for (int k = 0; k < kFreshDraws; ++k)
                    consider(sources.list[std::size_t(rng.uniform_int(0, int(sources.list.size())))]);
                m_matches[q] = best;
                m_distances[q] = best_d;
            }
        });
    }

    // M step: every pixel = robust weighted mean of the matched windows covering it, each
    // shifted to its output window's mean. Gathered per pixel in a fixed order (deterministic).
    void blend(const SourceSet& sources, bool sharp) {
        const int side = sources.side, w = m_out.width(), h = m_out.height();
        const std::size_t nx = m_xs.size();
        const double pixels = double(side) * double(side);
        // Per window: weight and the level shift (output mean - source mean).
        std::vector<double> weight(m_matches.size()), shift(m_matches.size());
        double floor = 0;
        for (double d : m_distances) floor += d / pixels;
        floor = 1e-3 * floor / double(std::max<std::size_t>(m_distances.size(), 1)) + 1e-12;
        parallel_for(m_matches.size(), 256, [&](std::size_t begin, std::size_t end) {
            std::vector<float> window;
            for (std::size_t q = begin; q < end; ++q) {
                double mean = 0;
                output_window(q % nx, q / nx, side, window, mean);
                weight[q] = std::pow(m_distances[q] / pixels + floor, kRobustPower);
                shift[q] = mean - sources.mean(m_matches[q]);
            }
        });
        // Windows covering each column / row: (grid index, offset inside the window).
        auto covering = [&](const std::vector<int>& origins, int canvas) {
            std::vector<std::vector<std::pair<int, int>>> lists(static_cast<std::size_t>(canvas));
            for (std::size_t k = 0; k < origins.size(); ++k)
                for (int o = 0; o < side; ++o) {
                    const int c = m_options.tileable ? (origins[k] + o) % canvas : origins[k] + o;
                    if (c < canvas) lists[std::size_t(c)].push_back({int(k), o});
                }
            return lists;
        };
        const auto columns = covering(m_xs, w), rows = covering(m_ys, h);
        Image next(w, h, 1);
        parallel_for(std::size_t(h), 4, [&](std::size_t y0, std::size_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < w; ++x) {
                    double sum = 0, total = 0, best_weight = -1, best = 0;
                    for (const auto& [j, oy] : rows[std::size_t(y)])
                        for (const auto& [i, ox] : columns[std::size_t(x)]) {
                            const std::size_t q = std::size_t(j) * nx + std::size_t(i);
                            const Source& s = m_matches[q];
                            const double v = m_exemplars[std::size_t(s.exemplar)].at(s.x + ox, s.y + oy, 0) + shift[q];
                            sum += weight[q] * v;
                            total += weight[q];
                            if (weight[q] > best_weight) best_weight = weight[q], best = v;
                        }
                    next.at(x, y, 0) = total <= 0 ? m_out.at(x, y, 0) : sharp ? float(best) : float(sum / total);
                }
        });
        m_out = std::move(next);
    }

    const std::vector<Image>& m_exemplars;
    const std::vector<Image>& m_masks;
    TextureOptimizationOptions m_options;
    Image m_out;
    std::vector<int> m_xs, m_ys;
    std::vector<Source> m_matches;
    std::vector<double> m_distances;
};

}  // namespace

Image optimize_texture(const std::vector<Image>& exemplars, const std::vector<Image>& masks, const Image& initial,
                       const TextureOptimizationOptions& options) {
    if (exemplars.empty()) throw_error("texture optimisation: no exemplar given");
    if (initial.channels() != 1) throw_error("texture optimisation: expected a 1-channel initial texture");
    if (options.windows.empty()) throw_error("texture optimisation: no window side given");
    if (options.iterations.empty() || options.iterations.size() > options.windows.size())
        throw_error("texture optimisation: expected 1 to {} iteration counts (one per window side), got {}",
                    options.windows.size(),
                    options.iterations.size());
    for (int n : options.iterations)
        if (n < 1) throw_error("texture optimisation: iterations must be >= 1, got {}", n);
    if (!(options.min_coverage >= 0.0f && options.min_coverage <= 1.0f))
        throw_error("texture optimisation: the minimum region coverage must be in [0, 1], got {}", options.min_coverage);
    for (int side : options.windows)
        if (side < 4) throw_error("texture optimisation: window sides must be >= 4, got {}", side);
    if (!masks.empty() && masks.size() != exemplars.size())
        throw_error("texture optimisation: {} region masks for {} exemplars", masks.size(), exemplars.size());
    for (std::size_t i = 0; i < exemplars.size(); ++i) {
        if (exemplars[i].channels() != 1) throw_error("texture optimisation: expected 1-channel exemplars");
        if (i < masks.size() && !masks[i].empty() &&
            (masks[i].width() != exemplars[i].width() || masks[i].height() != exemplars[i].height()))
            throw_error("texture optimisation: region mask {} does not match its exemplar's size", i);
    }
    Optimizer optimizer(exemplars, masks, initial, options);
    return optimizer.run();
}

}  // namespace tdf
