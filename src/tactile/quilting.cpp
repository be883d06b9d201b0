#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/tactile/quilting.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>

#include "fftw_plan_impl.h"

namespace tdf {

namespace {

// Sides of a block that overlap already placed pixels (a bit set).
enum Side : unsigned { kLeft = 1, kTop = 2, kRight = 4, kBottom = 8, kSideTypes = 16 };

// Placed pixels that count as "the same" as a candidate: relative to the overlap's energy,
// far above FFT rounding (~1e-15) and far below any real mismatch.
constexpr double kZeroErrorRelative = 1e-9;
// Error of a candidate that may not be used (see QuiltOptions::min_contrast).
constexpr double kExcluded = std::numeric_limits<double>::infinity();

struct Grid {
    int n = 0;        // blocks per side
    int block = 0;    // B
    int overlap = 0;  // O
    int stride = 0;   // B - O
    int canvas = 0;   // canvas side (tileable: n * stride, wrapping)
    bool wrap = false;
    int margin = 1;   // pixels beyond its footprint that placing a block reads (seams, feathering)

    int origin(int i) const { return i * stride; }
    // Canvas coordinate of block-local offset `k` from origin `o`.
    int at(int o, int k) const { return wrap ? (o + k) % canvas : o + k; }
    // The same for offsets around the footprint too (k < 0 or k >= block); false off a
    // non-wrapping canvas.
    bool around(int o, int k, int& g) const {
        g = o + k;
        if (wrap) g = (g % canvas + canvas) % canvas;
        return g >= 0 && g < canvas;
    }
    unsigned sides(int row, int col) const {
        unsigned s = 0;
        if (col > 0) s |= kLeft;
        if (row > 0) s |= kTop;
        if (wrap && col == n - 1 && n > 1) s |= kRight;
        if (wrap && row == n - 1 && n > 1) s |= kBottom;
        return s;
    }
    // True when footprints starting at a and b (one axis) share pixels.
    bool intersect(int a, int b) const {
        // Placing a block reads `margin` pixels around its footprint.
        const int reach = block + margin;
        if (!wrap) return std::abs(a - b) < reach;
        const int d = ((b - a) % canvas + canvas) % canvas;
        return d < reach || canvas - d < reach;
    }
};

// The B x B overlap mask of a side set: 1 where placed pixels lie under the block.
std::vector<std::uint8_t> side_mask(unsigned sides, int block, int overlap) {
    std::vector<std::uint8_t> mask(std::size_t(block) * std::size_t(block), 0);
    for (int y = 0; y < block; ++y)
        for (int x = 0; x < block; ++x)
            mask[std::size_t(y) * std::size_t(block) + std::size_t(x)] =
                ((sides & kLeft) && x < overlap) || ((sides & kTop) && y < overlap) ||
                ((sides & kRight) && x >= block - overlap) || ((sides & kBottom) && y >= block - overlap);
    return mask;
}

// One exemplar prepared for FFT candidate search.
struct Exemplar {
    const Image* image = nullptr;
    int width = 0, height = 0, channels = 0;
    int positions_x = 0, positions_y = 0;  // candidate top-left offsets per axis
    fftw::Plan forward, inverse;
    std::vector<fftw::ComplexBuffer> spectra;  // F(E_c) per channel
    // Per side set: sum over the mask of sum_c E_c^2 for every candidate position.
    std::vector<std::vector<double>> masked_energy;
    // Per candidate: 1 when its contrast is below QuiltOptions::min_contrast.
    std::vector<std::uint8_t> excluded;

    std::size_t spectrum_size() const { return std::size_t(height) * std::size_t(width / 2 + 1); }
    std::size_t candidates() const { return std::size_t(positions_x) * std::size_t(positions_y); }
};

// Per-worker buffers, reused across blocks (taken from a pool, never allocated per block).
struct Scratch {
    fftw::RealBuffer real;
    fftw::ComplexBuffer spectrum, product;
    std::vector<std::vector<double>> errors;  // per exemplar, per candidate
    std::vector<float> pixel_error;           // B x B, new vs placed
    std::vector<double> path_cost;
    std::vector<std::uint8_t> keep_old;  // B x B
    std::vector<float> strip_cost;       // B x O, one side's cost along its seam
    std::vector<float> start_extra, end_extra;  // O each: cost of the seam left at a cut's ends
    std::vector<float> weight;    // B x B, weight of the new block (feathering)
    std::vector<float> extended;  // (B + 2 feather)^2: the weights and the ring around them
    std::vector<float> blurred;   // B x (B + 2 feather): blurred along x
    std::vector<int> seam;
    std::vector<std::pair<int, int>> seam_pixels;  // block-local (x, y) on this block's cuts
};

class ScratchPool {
public:
    explicit ScratchPool(std::function<std::unique_ptr<Scratch>()> make) : m_make(std::move(make)) {}
    std::unique_ptr<Scratch> take() {
        {
            std::lock_guard<std::mutex> lock(m_mutex);
            if (!m_free.empty()) {
                auto s = std::move(m_free.back());
                m_free.pop_back();
                return s;
            }
        }
        return m_make();
    }
    void give(std::unique_ptr<Scratch> s) {
        std::lock_guard<std::mutex> lock(m_mutex);
        m_free.push_back(std::move(s));
    }

private:
    std::function<std::unique_ptr<Scratch>()> m_make;
    std::mutex m_mutex;
    std::vector<std::unique_ptr<Scratch>> m_free;
};

// Minimum-cost 8-neighbour path through a rows x cols cost map, one column per row, ties to
// the smaller column (the reference's argmin order -1, 0, +1). `first_row_extra` and
// `last_row_extra` (cols values each) add to the cost of starting or ending in a column.
// Writes seam[row] = column.
void min_cut_path(const float* cost, int rows, int cols, const float* first_row_extra,
                  const float* last_row_extra, std::vector<double>& total, std::vector<int>& seam) {
    total.assign(std::size_t(rows) * std::size_t(cols), 0.0);
    for (int c = 0; c < cols; ++c) total[std::size_t(c)] = double(cost[c]) + double(first_row_extra[c]);
    for (int r = 1; r < rows; ++r)
        for (int c = 0; c < cols; ++c) {
            double best = total[std::size_t(r - 1) * std::size_t(cols) + std::size_t(c)];
            if (c > 0)
                best = std::min(best, total[std::size_t(r - 1) * std::size_t(cols) + std::size_t(c - 1)]);
            if (c + 1 < cols)
                best = std::min(best, total[std::size_t(r - 1) * std::size_t(cols) + std::size_t(c + 1)]);
            total[std::size_t(r) * std::size_t(cols) + std::size_t(c)] =
                best + cost[std::size_t(r) * std::size_t(cols) + std::size_t(c)];
        }
    seam.resize(std::size_t(rows));
    const double* last = &total[std::size_t(rows - 1) * std::size_t(cols)];
    int c = 0;
    for (int k = 1; k < cols; ++k)
        if (last[k] + last_row_extra[k] < last[c] + last_row_extra[c]) c = k;
    seam[std::size_t(rows - 1)] = c;
    for (int r = rows - 2; r >= 0; --r) {
        const double* row = &total[std::size_t(r) * std::size_t(cols)];
        int best = c;
        for (int d = -1; d <= 1; ++d) {
            const int k = c + d;
            if (k >= 0 && k < cols && (row[k] < row[best] || (row[k] == row[best] && k < best))) best = k;
        }
        c = best;
        seam[std::size_t(r)] = c;
    }
}

class Quilter {
public:
    Quilter(const std::vector<Image>& images, const QuiltOptions& options,
            const std::vector<std::string>& names, const std::vector<Image>& masks);
    QuiltResult run();

private:
    void prepare_exemplar(Exemplar& e, const Image& image);
    void exclude_flat_candidates();
    void new_block_weights(int ox, int oy, unsigned sides, Scratch& s) const;
    void place_block(int row, int col, Scratch& s, double& cut_error, double& random_error);
    void search(int row, int col, unsigned sides, Scratch& s, int& chosen_exemplar, int& chosen_x,
                int& chosen_y, double& random_error);
    void paste(int row, int col, unsigned sides, const Exemplar& e, int ex, int ey, Scratch& s,
               double& cut_error);

    QuiltOptions m_options;
    Grid m_grid;
    std::vector<Exemplar> m_exemplars;
    std::vector<std::vector<std::uint8_t>> m_masks;  // per side set
    std::vector<std::size_t> m_mask_count;
    std::vector<Image> m_regions;  // per exemplar, empty = all
    double m_coverage_needed = 1;
    Image m_canvas, m_seams;
    std::vector<std::uint8_t> m_filled;
    int m_channels = 0;
};

Quilter::Quilter(const std::vector<Image>& images, const QuiltOptions& options,
                 const std::vector<std::string>& names, const std::vector<Image>& masks)
    : m_options(options), m_regions(masks) {
    auto name = [&](std::size_t i) { return i < names.size() ? names[i] : fmt::format("exemplar {}", i); };
    if (images.empty()) throw_error("quilting: no exemplar patch given");
    if (options.block < 4) throw_error("quilting: --block must be at least 4 pixels, got {}", options.block);
    if (!(options.overlap > 0.0f && options.overlap <= 0.5f))
        throw_error("quilting: --overlap must be in (0, 0.5], got {}", options.overlap);
    if (!(options.tolerance >= 0.0f))
        throw_error("quilting: --tolerance must be >= 0, got {}", options.tolerance);
    if (!(options.min_coverage >= 0.0f && options.min_coverage <= 1.0f))
        throw_error("quilting: the minimum region coverage must be in [0, 1], got {}", options.min_coverage);
    if (!masks.empty() && masks.size() != images.size())
        throw_error("quilting: {} region masks for {} exemplars", masks.size(), images.size());
    for (std::size_t i = 0; i < masks.size(); ++i)
        if (!masks[i].empty() && (masks[i].width() != images[i].width() ||
                                  masks[i].height() != images[i].height() || masks[i].channels() != 1))
            throw_error("{}: the region mask does not match the exemplar's size", name(i));
    if (!(options.min_contrast >= 0.0f && options.min_contrast <= 1.0f))
        throw_error("quilting: --min-contrast must be in [0, 1], got {}", options.min_contrast);
    if (options.feather < 0 || 2 * options.feather >= options.block)
        throw_error("quilting: --feather must be in [0, block / 2), got {}", options.feather);
    if (options.size < options.block)
        throw_error("quilting: --size {} is smaller than the block {}", options.size, options.block);
    m_grid.block = options.block;
    m_grid.overlap = std::max(1, int(options.overlap * float(options.block)));
    m_grid.stride = m_grid.block - m_grid.overlap;
    m_grid.wrap = options.tileable;
    m_grid.margin = std::max(1, options.feather);
    if (options.tileable) {
        m_grid.canvas = quilt_output_side(options);
        m_grid.n = m_grid.canvas / m_grid.stride;
    } else {
        m_grid.n = 1 + (options.size - m_grid.block + m_grid.stride - 1) / m_grid.stride;
        m_grid.canvas = m_grid.block + (m_grid.n - 1) * m_grid.stride;
    }
    m_channels = images[0].channels();
    for (std::size_t i = 0; i < images.size(); ++i) {
        const Image& image = images[i];
        if (image.channels() != m_channels)
            throw_error(
                "{}: {} channels, but the first exemplar has {}", name(i), image.channels(), m_channels);
        if (image.width() < options.block || image.height() < options.block)
            throw_error("{}: the patch ({}x{}) is smaller than the block size {}",
                        name(i),
                        image.width(),
                        image.height(),
                        options.block);
        if (!image.all_finite()) throw_error("{}: the patch contains NaN or infinite values", name(i));
    }
    for (unsigned sides = 0; sides < kSideTypes; ++sides) {
        m_masks.push_back(side_mask(sides, m_grid.block, m_grid.overlap));
        m_mask_count.push_back(std::size_t(std::count(m_masks.back().begin(), m_masks.back().end(), 1)));
    }
    m_exemplars.resize(images.size());
    for (std::size_t i = 0; i < images.size(); ++i) prepare_exemplar(m_exemplars[i], images[i]);
    exclude_flat_candidates();
}

// Standard deviation of every candidate block (all channels), from summed-area tables; with
// `mean`, the block's mean instead (the coverage of a 0/1 mask).
std::vector<double> block_contrast(const Image& image, int block, bool want_mean) {
    const int w = image.width(), h = image.height(), channels = image.channels();
    std::vector<double> sum(std::size_t(w + 1) * std::size_t(h + 1), 0.0), sum2(sum.size(), 0.0);
    auto at = [&](int x, int y) { return std::size_t(y) * std::size_t(w + 1) + std::size_t(x); };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            double v = 0, v2 = 0;
            for (int c = 0; c < channels; ++c)
                v += image.at(x, y, c), v2 += double(image.at(x, y, c)) * image.at(x, y, c);
            sum[at(x + 1, y + 1)] = v + sum[at(x, y + 1)] + sum[at(x + 1, y)] - sum[at(x, y)];
            sum2[at(x + 1, y + 1)] = v2 + sum2[at(x, y + 1)] + sum2[at(x + 1, y)] - sum2[at(x, y)];
        }
    const int px = w - block + 1, py = h - block + 1;
    const double n = double(block) * block * channels;
    std::vector<double> contrast(std::size_t(px) * std::size_t(py));
    for (int y = 0; y < py; ++y)
        for (int x = 0; x < px; ++x) {
            auto box = [&](const std::vector<double>& t) {
                return t[at(x + block, y + block)] - t[at(x, y + block)] - t[at(x + block, y)] + t[at(x, y)];
            };
            const double mean = box(sum) / n;
            contrast[std::size_t(y) * std::size_t(px) + std::size_t(x)] =
                want_mean ? mean : std::sqrt(std::max(box(sum2) / n - mean * mean, 0.0));
        }
    return contrast;
}

void Quilter::exclude_flat_candidates() {
    // Blocks outside the textured region first: the guard below compares with the median of
    // the region's blocks, not with the flat gel around a contact.
    std::vector<std::vector<double>> coverage;
    std::vector<double> all;
    for (std::size_t i = 0; i < m_exemplars.size(); ++i) {
        const Exemplar& e = m_exemplars[i];
        const bool masked = i < m_regions.size() && !m_regions[i].empty();
        coverage.push_back(masked ? block_contrast(m_regions[i], m_grid.block, true)
                                  : std::vector<double>(e.candidates(), 1.0));
        all.insert(all.end(), coverage.back().begin(), coverage.back().end());
    }
    const std::size_t keep = std::min(all.size(), std::max<std::size_t>(64, all.size() / 50));
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(keep - 1), all.end(), std::greater<double>());
    const double needed = std::min(double(m_options.min_coverage), all[keep - 1]);
    m_coverage_needed = needed;
    for (std::size_t i = 0; i < m_exemplars.size(); ++i) {
        m_exemplars[i].excluded.resize(coverage[i].size());
        for (std::size_t k = 0; k < coverage[i].size(); ++k)
            m_exemplars[i].excluded[k] = coverage[i][k] < needed - 1e-9;
    }

    std::vector<std::vector<double>> contrast;
    all.clear();
    for (std::size_t i = 0; i < m_exemplars.size(); ++i) {
        contrast.push_back(block_contrast(*m_exemplars[i].image, m_grid.block, false));
        for (std::size_t k = 0; k < contrast[i].size(); ++k)
            if (!m_exemplars[i].excluded[k]) all.push_back(contrast[i][k]);
    }
    std::nth_element(all.begin(), all.begin() + std::ptrdiff_t(all.size() / 2), all.end());
    const double threshold = double(m_options.min_contrast) * all[all.size() / 2];
    for (std::size_t i = 0; i < m_exemplars.size(); ++i)
        // Strictly below: with min_contrast <= 1 at least half of the candidates stay.
        for (std::size_t k = 0; k < contrast[i].size(); ++k)
            if (contrast[i][k] < threshold) m_exemplars[i].excluded[k] = 1;
}

void Quilter::prepare_exemplar(Exemplar& e, const Image& image) {
    e.image = &image;
    e.width = image.width();
    e.height = image.height();
    e.channels = image.channels();
    e.positions_x = e.width - m_grid.block + 1;
    e.positions_y = e.height - m_grid.block + 1;
    const std::size_t pixels = image.pixel_count();
    fftw::RealBuffer real = fftw::alloc_real(pixels);
    fftw::ComplexBuffer energy_spectrum = fftw::alloc_complex(e.spectrum_size());
    fftw::ComplexBuffer product = fftw::alloc_complex(e.spectrum_size());
    e.forward = fftw::plan_r2c(e.width, e.height, real.get(), energy_spectrum.get());
    e.inverse = fftw::plan_c2r(e.width, e.height, product.get(), real.get());

    for (int c = 0; c < e.channels; ++c) {
        for (std::size_t p = 0; p < pixels; ++p)
            real[p] = image.data()[p * std::size_t(e.channels) + std::size_t(c)];
        e.spectra.push_back(fftw::alloc_complex(e.spectrum_size()));
        fftw_execute_dft_r2c(e.forward.get(), real.get(), e.spectra.back().get());
    }
    for (std::size_t p = 0; p < pixels; ++p) {
        double sum = 0;
        for (int c = 0; c < e.channels; ++c)
            sum += double(image.data()[p * std::size_t(e.channels) + std::size_t(c)]) *
                   image.data()[p * std::size_t(e.channels) + std::size_t(c)];
        real[p] = sum;
    }
    fftw_execute_dft_r2c(e.forward.get(), real.get(), energy_spectrum.get());

    // Which side sets occur on this grid (only those need the masked energy).
    std::vector<bool> used(kSideTypes, false);
    for (int r = 0; r < m_grid.n; ++r)
        for (int c = 0; c < m_grid.n; ++c) used[m_grid.sides(r, c)] = true;
    e.masked_energy.resize(kSideTypes);
    fftw::ComplexBuffer mask_spectrum = fftw::alloc_complex(e.spectrum_size());
    const double normalisation = 1.0 / double(pixels);
    for (unsigned sides = 1; sides < kSideTypes; ++sides) {
        if (!used[sides]) continue;
        std::fill(real.get(), real.get() + pixels, 0.0);
        for (int y = 0; y < m_grid.block; ++y)
            for (int x = 0; x < m_grid.block; ++x)
                real[std::size_t(y) * std::size_t(e.width) + std::size_t(x)] =
                    m_masks[sides][std::size_t(y) * std::size_t(m_grid.block) + std::size_t(x)];
        fftw_execute_dft_r2c(e.forward.get(), real.get(), mask_spectrum.get());
        // corr(E^2, M) = ifft(F(E^2) * conj(F(M))).
        for (std::size_t k = 0; k < e.spectrum_size(); ++k) {
            const double ar = energy_spectrum[k][0], ai = energy_spectrum[k][1];
            const double br = mask_spectrum[k][0], bi = -mask_spectrum[k][1];
            product[k][0] = ar * br - ai * bi;
            product[k][1] = ar * bi + ai * br;
        }
        fftw_execute_dft_c2r(e.inverse.get(), product.get(), real.get());
        auto& out = e.masked_energy[sides];
        out.resize(e.candidates());
        for (int y = 0; y < e.positions_y; ++y)
            for (int x = 0; x < e.positions_x; ++x)
                out[std::size_t(y) * std::size_t(e.positions_x) + std::size_t(x)] =
                    real[std::size_t(y) * std::size_t(e.width) + std::size_t(x)] * normalisation;
    }
}

void Quilter::search(int row, int col, unsigned sides, Scratch& s, int& chosen_exemplar, int& chosen_x,
                     int& chosen_y, double& random_error) {
    Rng rng = Rng::stream(m_options.seed, std::uint64_t(row) * std::uint64_t(m_grid.n) + std::uint64_t(col));
    const int b = m_grid.block;
    const int ox = m_grid.origin(col), oy = m_grid.origin(row);
    const std::vector<std::uint8_t>& mask = m_masks[sides];
    const double count = double(m_mask_count[sides]) * double(m_channels);

    double template_energy = 0;
    for (int y = 0; y < b; ++y)
        for (int x = 0; x < b; ++x) {
            if (!mask[std::size_t(y) * std::size_t(b) + std::size_t(x)]) continue;
            const int cx = m_grid.at(ox, x), cy = m_grid.at(oy, y);
            TDF_CHECK(m_filled[std::size_t(cy) * std::size_t(m_grid.canvas) + std::size_t(cx)]);
            for (int c = 0; c < m_channels; ++c)
                template_energy += double(m_canvas.at(cx, cy, c)) * m_canvas.at(cx, cy, c);
        }

    double minimum = std::numeric_limits<double>::infinity();
    double error_sum = 0;
    std::size_t error_count = 0;
    const double zero = kZeroErrorRelative * template_energy / std::max(count, 1.0);
    for (std::size_t i = 0; i < m_exemplars.size(); ++i) {
        const Exemplar& e = m_exemplars[i];
        std::vector<double>& errors = s.errors[i];
        if (sides == 0) {  // the first block: every allowed position is equally good
            for (std::size_t k = 0; k < errors.size(); ++k) errors[k] = e.excluded[k] ? kExcluded : 1.0;
            continue;
        }
        // -2 * corr(E, M * T), summed over channels in the frequency domain.
        for (std::size_t k = 0; k < e.spectrum_size(); ++k) s.product[k][0] = s.product[k][1] = 0.0;
        for (int c = 0; c < m_channels; ++c) {
            std::fill(s.real.get(), s.real.get() + std::size_t(e.width) * std::size_t(e.height), 0.0);
            for (int y = 0; y < b; ++y)
                for (int x = 0; x < b; ++x)
                    if (mask[std::size_t(y) * std::size_t(b) + std::size_t(x)])
                        s.real[std::size_t(y) * std::size_t(e.width) + std::size_t(x)] =
                            m_canvas.at(m_grid.at(ox, x), m_grid.at(oy, y), c);
            fftw_execute_dft_r2c(e.forward.get(), s.real.get(), s.spectrum.get());
            const fftw_complex* ec = e.spectra[std::size_t(c)].get();
            for (std::size_t k = 0; k < e.spectrum_size(); ++k) {
                const double ar = ec[k][0], ai = ec[k][1];
                const double br = s.spectrum[k][0], bi = -s.spectrum[k][1];
                s.product[k][0] += ar * br - ai * bi;
                s.product[k][1] += ar * bi + ai * br;
            }
        }
        fftw_execute_dft_c2r(e.inverse.get(), s.product.get(), s.real.get());
        const double scale = -2.0 / (double(e.width) * double(e.height));
        const std::vector<double>& energy = e.masked_energy[sides];
        for (int y = 0; y < e.positions_y; ++y)
            for (int x = 0; x < e.positions_x; ++x) {
                const std::size_t k = std::size_t(y) * std::size_t(e.positions_x) + std::size_t(x);
                const double ssd = energy[k] +
                                   scale * s.real[std::size_t(y) * std::size_t(e.width) + std::size_t(x)] +
                                   template_energy;
                if (e.excluded[k]) {
                    errors[k] = kExcluded;
                    continue;
                }
                const double error = std::max(ssd, 0.0) / count;
                errors[k] = error;
                error_sum += error;
                ++error_count;
                if (error > zero) minimum = std::min(minimum, error);
            }
    }
    random_error = error_count ? error_sum / double(error_count) : 0.0;

    // Accept all non-zero errors below (1 + tolerance) * minimum; if every candidate is a
    // verbatim match (a constant exemplar), accept them all.
    const bool all_zero = !std::isfinite(minimum);
    const double limit = (1.0 + double(m_options.tolerance)) * minimum;
    auto accepted = [&](double error) {
        return error != kExcluded && (all_zero || sides == 0 || (error > zero && error < limit));
    };
    std::size_t total = 0;
    for (const auto& errors : s.errors)
        for (double error : errors) total += accepted(error);
    TDF_CHECK(total > 0);
    std::size_t pick = std::size_t(rng.uniform_int(0, int(total)));
    for (std::size_t i = 0; i < m_exemplars.size(); ++i) {
        const Exemplar& e = m_exemplars[i];
        for (std::size_t k = 0; k < s.errors[i].size(); ++k) {
            if (!accepted(s.errors[i][k])) continue;
            if (pick-- == 0) {
                chosen_exemplar = int(i);
                chosen_x = int(k % std::size_t(e.positions_x));
                chosen_y = int(k / std::size_t(e.positions_x));
                return;
            }
        }
    }
    TDF_CHECK(false);
}

void Quilter::paste(int row, int col, unsigned sides, const Exemplar& e, int ex, int ey, Scratch& s,
                    double& cut_error) {
    const int b = m_grid.block, o = m_grid.overlap;
    const int ox = m_grid.origin(col), oy = m_grid.origin(row);
    const Image& source = *e.image;
    // Squared difference, averaged over channels, of the exemplar's and the canvas's pixels.
    const auto difference2 = [&](int sx, int sy, int gx, int gy) {
        float d2 = 0;
        for (int c = 0; c < m_channels; ++c) {
            const float d = source.at(sx, sy, c) - m_canvas.at(gx, gy, c);
            d2 += d * d;
        }
        return d2 / float(m_channels);
    };
    // Per-pixel error where placed pixels lie.
    for (int y = 0; y < b; ++y)
        for (int x = 0; x < b; ++x)
            s.pixel_error[std::size_t(y) * std::size_t(b) + std::size_t(x)] =
                m_masks[sides][std::size_t(y) * std::size_t(b) + std::size_t(x)]
                    ? difference2(ex + x, ey + y, m_grid.at(ox, x), m_grid.at(oy, y))
                    : 0.0f;
    const auto error_at = [&](int x, int y) {
        return s.pixel_error[std::size_t(y) * std::size_t(b) + std::size_t(x)];
    };
    // Error on the ring of pixels just outside the block: the exemplar's pixel there against
    // the canvas's. False where either is missing (exemplar border, unfilled or outside canvas).
    const auto ring_error = [&](int x, int y, float& error) {
        const int sx = ex + x, sy = ey + y;
        if (sx < 0 || sy < 0 || sx >= source.width() || sy >= source.height()) return false;
        int gx = 0, gy = 0;
        if (!m_grid.around(ox, x, gx) || !m_grid.around(oy, y, gy)) return false;
        if (!m_filled[std::size_t(gy) * std::size_t(m_grid.canvas) + std::size_t(gx)]) return false;
        error = difference2(sx, sy, gx, gy);
        return true;
    };
    std::fill(s.keep_old.begin(), s.keep_old.end(), 0);
    s.seam_pixels.clear();
    double seam_sum = 0;
    std::size_t seam_pixels = 0;
    // Each side: a path across its strip, the placed content kept on the outer side of it.
    // Horizontal strips are cut as vertical ones on the transposed cost.
    std::vector<float>& cost = s.strip_cost;
    for (unsigned side : {kLeft, kTop, kRight, kBottom}) {
        if (!(sides & side)) continue;
        const bool vertical = side == kLeft || side == kRight;
        const int offset = (side == kLeft || side == kTop) ? 0 : b - o;
        // cost(r, k): r along the seam (0..b), k across the strip (0..o).
        for (int r = 0; r < b; ++r)
            for (int k = 0; k < o; ++k)
                cost[std::size_t(r) * std::size_t(o) + std::size_t(k)] =
                    vertical ? error_at(offset + k, r) : error_at(r, offset + k);
        // Left/top strips keep the old pixels before the cut, right/bottom ones after it.
        const bool near_side = offset == 0;
        // The new pixels a cut leaves at either end of its strip border the old ones beyond the
        // block there, unless a crossing strip cuts that corner: that border is a seam too (the
        // top cut ending mid-strip at the block's right edge left a vertical step the next block
        // kept above its own top cut).
        const unsigned start_crossing = vertical ? kTop : kLeft, end_crossing = vertical ? kBottom : kRight;
        for (int end = 0; end < 2; ++end) {
            std::vector<float>& extra = end == 0 ? s.start_extra : s.end_extra;
            std::fill(extra.begin(), extra.end(), 0.0f);
            if (sides & (end == 0 ? start_crossing : end_crossing)) continue;
            const int r = end == 0 ? 0 : b - 1, step = end == 0 ? -1 : 1;
            for (int k = 0; k < o; ++k) {
                const int x = vertical ? offset + k : r, y = vertical ? r : offset + k;
                float outer = 0;
                if (!ring_error(vertical ? x : x + step, vertical ? y + step : y, outer)) continue;
                const float seam = error_at(x, y) + outer;
                // Cut k leaves new pixels at k.. (near side) or ..k (far side).
                if (near_side)
                    for (int j = 0; j <= k; ++j) extra[std::size_t(j)] += seam;
                else
                    for (int j = k; j < o; ++j) extra[std::size_t(j)] += seam;
            }
        }
        min_cut_path(cost.data(), b, o, s.start_extra.data(), s.end_extra.data(), s.path_cost, s.seam);
        for (int r = 0; r < b; ++r) {
            const int cut = s.seam[std::size_t(r)];
            s.seam_pixels.push_back(vertical ? std::pair<int, int>{offset + cut, r} : std::pair<int, int>{r, offset + cut});
            seam_sum += vertical ? error_at(offset + cut, r) : error_at(r, offset + cut);
            ++seam_pixels;
            // Left/top: pixels before the cut stay; right/bottom: pixels after it stay.
            const int first = offset == 0 ? 0 : cut + 1, last = offset == 0 ? cut : o;
            for (int k = first; k < last; ++k) {
                const int x = vertical ? offset + k : r, y = vertical ? r : offset + k;
                s.keep_old[std::size_t(y) * std::size_t(b) + std::size_t(x)] = 1;
            }
        }
    }
    cut_error = seam_pixels ? seam_sum / double(seam_pixels) : 0.0;
    new_block_weights(ox, oy, sides, s);
    const std::vector<std::uint8_t>& placed = m_masks[sides];
    for (int y = 0; y < b; ++y)
        for (int x = 0; x < b; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(b) + std::size_t(x);
            const float w = s.weight[i];
            if (w == 0.0f) continue;
            const int cx = m_grid.at(ox, x), cy = m_grid.at(oy, y);
            for (int c = 0; c < m_channels; ++c) {
                float& out = m_canvas.at(cx, cy, c);
                const float fresh = source.at(ex + x, ey + y, c);
                out = placed[i] && w < 1.0f ? out + w * (fresh - out) : fresh;
            }
            m_filled[std::size_t(cy) * std::size_t(m_grid.canvas) + std::size_t(cx)] = 1;
            if (w == 1.0f) m_seams.at(cx, cy, 0) = 0.0f;  // covered by new content
        }
    for (const auto& [x, y] : s.seam_pixels) m_seams.at(m_grid.at(ox, x), m_grid.at(oy, y), 0) = 1.0f;
}

void Quilter::new_block_weights(int ox, int oy, unsigned sides, Scratch& s) const {
    const int b = m_grid.block, f = m_options.feather;
    for (std::size_t i = 0; i < s.weight.size(); ++i) s.weight[i] = s.keep_old[i] ? 0.0f : 1.0f;
    if (f == 0) return;  // the reference's hard cut
    // Box-blur the cut across +-f pixels (separable), only where placed pixels exist to blend
    // with: the step a cut leaves in a height map becomes a ramp. Beyond the block the weight is
    // 0 where the canvas holds old pixels, so a cut at the block's edge is ramped like any other
    // (clamping to the block left those cuts hard: the lines at the blocks' edges stepped 1.2x).
    const int e = b + 2 * f;
    for (int y = -f; y < b + f; ++y)
        for (int x = -f; x < b + f; ++x) {
            float w;
            if (x >= 0 && y >= 0 && x < b && y < b) {
                w = s.weight[std::size_t(y) * std::size_t(b) + std::size_t(x)];
            } else {
                int gx = 0, gy = 0;
                const bool inside = m_grid.around(ox, x, gx) && m_grid.around(oy, y, gy);
                w = inside && m_filled[std::size_t(gy) * std::size_t(m_grid.canvas) + std::size_t(gx)] ? 0.0f : 1.0f;
            }
            s.extended[std::size_t(y + f) * std::size_t(e) + std::size_t(x + f)] = w;
        }
    const float scale = 1.0f / float(2 * f + 1);
    for (int y = 0; y < e; ++y)  // along x, for the block's columns
        for (int x = 0; x < b; ++x) {
            float sum = 0;
            for (int d = 0; d <= 2 * f; ++d) sum += s.extended[std::size_t(y) * std::size_t(e) + std::size_t(x + d)];
            s.blurred[std::size_t(y) * std::size_t(b) + std::size_t(x)] = sum * scale;
        }
    for (int y = 0; y < b; ++y)  // along y
        for (int x = 0; x < b; ++x) {
            float sum = 0;
            for (int d = 0; d <= 2 * f; ++d) sum += s.blurred[std::size_t(y + d) * std::size_t(b) + std::size_t(x)];
            s.weight[std::size_t(y) * std::size_t(b) + std::size_t(x)] = sum * scale;
        }
    const std::vector<std::uint8_t>& placed = m_masks[sides];
    for (std::size_t i = 0; i < s.weight.size(); ++i)
        if (!placed[i]) s.weight[i] = 1.0f;
}

void Quilter::place_block(int row, int col, Scratch& s, double& cut_error, double& random_error) {
    const unsigned sides = m_grid.sides(row, col);
    int exemplar = 0, x = 0, y = 0;
    search(row, col, sides, s, exemplar, x, y, random_error);
    paste(row, col, sides, m_exemplars[std::size_t(exemplar)], x, y, s, cut_error);
}

QuiltResult Quilter::run() {
    const int n = m_grid.n;
    m_canvas = Image(m_grid.canvas, m_grid.canvas, m_channels);
    m_seams = Image(m_grid.canvas, m_grid.canvas, 1);
    m_filled.assign(std::size_t(m_grid.canvas) * std::size_t(m_grid.canvas), 0);

    // Dependency levels: a block comes after every earlier (raster-order) block it overlaps.
    // Blocks of one level never overlap, so placing them concurrently equals raster order.
    const int reach = (m_grid.block + m_grid.stride - 1) / m_grid.stride;
    std::vector<int> level(std::size_t(n) * std::size_t(n), 0);
    int levels = 0;
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            int l = 0;
            for (int dr = -reach; dr <= reach; ++dr)
                for (int dc = -reach; dc <= reach; ++dc) {
                    int nr = r + dr, nc = c + dc;
                    if (m_grid.wrap) nr = (nr + n) % n, nc = (nc + n) % n;
                    if (nr < 0 || nr >= n || nc < 0 || nc >= n) continue;
                    if (nr * n + nc >= r * n + c) continue;  // not earlier
                    if (m_grid.intersect(m_grid.origin(r), m_grid.origin(nr)) &&
                        m_grid.intersect(m_grid.origin(c), m_grid.origin(nc)))
                        l = std::max(l, level[std::size_t(nr) * std::size_t(n) + std::size_t(nc)] + 1);
                }
            level[std::size_t(r) * std::size_t(n) + std::size_t(c)] = l;
            levels = std::max(levels, l + 1);
        }
    std::vector<std::vector<int>> by_level(static_cast<std::size_t>(levels));
    for (int i = 0; i < n * n; ++i) by_level[std::size_t(level[std::size_t(i)])].push_back(i);

    std::size_t largest = 0;
    for (const Exemplar& e : m_exemplars)
        largest = std::max(largest, std::size_t(e.width) * std::size_t(e.height));
    ScratchPool pool([&] {
        auto s = std::make_unique<Scratch>();
        s->real = fftw::alloc_real(largest);
        s->spectrum = fftw::alloc_complex(largest);
        s->product = fftw::alloc_complex(largest);
        for (const Exemplar& e : m_exemplars) s->errors.emplace_back(e.candidates());
        s->pixel_error.resize(std::size_t(m_grid.block) * std::size_t(m_grid.block));
        s->keep_old.resize(s->pixel_error.size());
        s->weight.resize(s->pixel_error.size());
        const std::size_t extended = std::size_t(m_grid.block + 2 * m_options.feather);
        s->extended.resize(extended * extended);
        s->blurred.resize(extended * std::size_t(m_grid.block));
        s->strip_cost.resize(std::size_t(m_grid.block) * std::size_t(m_grid.overlap));
        s->start_extra.resize(std::size_t(m_grid.overlap));
        s->end_extra.resize(std::size_t(m_grid.overlap));
        return s;
    });
    std::vector<double> cut_errors(level.size()), random_errors(level.size());
    for (const std::vector<int>& blocks : by_level) {
        parallel_for(blocks.size(), 1, [&](std::size_t begin, std::size_t end) {
            std::unique_ptr<Scratch> s = pool.take();
            for (std::size_t i = begin; i < end; ++i) {
                const int b = blocks[i];
                place_block(b / n, b % n, *s, cut_errors[std::size_t(b)], random_errors[std::size_t(b)]);
            }
            pool.give(std::move(s));
        });
    }

    QuiltResult result;
    result.stats.blocks_per_side = n;
    result.stats.coverage_needed = m_coverage_needed;
    std::uint64_t per_block = 0;
    for (const Exemplar& e : m_exemplars) per_block += e.candidates();
    result.stats.candidates = per_block * std::uint64_t(n) * std::uint64_t(n);
    double cut_sum = 0, random_sum = 0;
    for (std::size_t i = 1; i < level.size(); ++i) cut_sum += cut_errors[i], random_sum += random_errors[i];
    const double placed = double(std::max<std::size_t>(level.size() - 1, 1));
    result.stats.mean_cut_error = cut_sum / placed;
    result.stats.mean_random_error = random_sum / placed;
    if (m_grid.wrap) {
        // The canvas is periodic, so any origin tiles alike. Boundary cuts gather at the edges of
        // the overlap strips (line pairs at a multiple of the stride carry ~1.3x the mean step);
        // starting half a stride later puts the wrap-around between two ordinary lines.
        const int shift = m_grid.stride / 2, w = m_grid.canvas;
        Image rolled(w, w, m_channels), seams(w, w, 1);
        for (int y = 0; y < w; ++y)
            for (int x = 0; x < w; ++x) {
                const int sx = (x + shift) % w, sy = (y + shift) % w;
                std::copy(m_canvas.pixel(sx, sy), m_canvas.pixel(sx, sy) + m_channels, rolled.pixel(x, y));
                seams.at(x, y, 0) = m_seams.at(sx, sy, 0);
            }
        m_canvas = std::move(rolled);
        m_seams = std::move(seams);
    }
    const int side = quilt_output_side(m_options);
    result.image = side == m_grid.canvas ? std::move(m_canvas) : Image(side, side, m_channels);
    result.seams = side == m_grid.canvas ? std::move(m_seams) : Image(side, side, 1);
    if (result.image.width() != m_grid.canvas)
        for (int y = 0; y < side; ++y) {
            std::copy(m_canvas.pixel(0, y),
                      m_canvas.pixel(0, y) + std::size_t(side) * std::size_t(m_channels),
                      result.image.pixel(0, y));
            std::copy(m_seams.pixel(0, y), m_seams.pixel(0, y) + std::size_t(side), result.seams.pixel(0, y));
        }
    return result;
}

}  // namespace

int quilt_output_side(const QuiltOptions& options) {
    if (!options.tileable) return options.size;
    const int overlap = std::max(1, int(options.overlap * float(options.block)));
    const int stride = std::max(1, options.block - overlap);
    // A wrap-around grid needs whole strides and at least two blocks' worth of room.
    const int n = std::max((options.block + stride - 1) / stride + 1, (options.size + stride / 2) / stride);
    return n * stride;
}

QuiltResult quilt(const std::vector<Image>& exemplars, const QuiltOptions& options,
                  const std::vector<std::string>& names, const std::vector<Image>& masks) {
    Quilter quilter(exemplars, options, names, masks);
    return quilter.run();
}

}  // namespace tdf
