#include <tdf/core/error.h>
#include <tdf/render/image_compare.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace tdf {

namespace {

// A channel of a multi-layer image: which layer and which channel within it.
struct ChannelRef {
    std::string name;
    const Image* image;
    int channel;
};

std::vector<ChannelRef> channels_of(const std::vector<ExrLayer>& layers) {
    std::vector<ChannelRef> out;
    for (const ExrLayer& layer : layers)
        for (int c = 0; c < layer.image.channels(); ++c) {
            const std::string& suffix = layer.channel_names[std::size_t(c)];
            out.push_back({layer.name.empty() ? suffix : layer.name + "." + suffix, &layer.image, c});
        }
    std::sort(
        out.begin(), out.end(), [](const ChannelRef& x, const ChannelRef& y) { return x.name < y.name; });
    return out;
}

// Hard coverage of a mask layer, or empty when there is none.
std::vector<std::uint8_t> hard_mask(const std::vector<ExrLayer>& layers) {
    for (const ExrLayer& layer : layers)
        if (layer.name == "mask" && layer.image.channels() == 1) {
            std::vector<std::uint8_t> m(layer.image.pixel_count());
            for (std::size_t i = 0; i < m.size(); ++i) m[i] = layer.image.data()[i] > 0.5f;
            return m;
        }
    return {};
}

// Pixels farther than `radius` from any change of coverage in either mask.
std::vector<std::uint8_t> interior_pixels(const std::vector<std::uint8_t>& ma,
                                          const std::vector<std::uint8_t>& mb, int w, int h, int radius) {
    std::vector<std::uint8_t> keep(std::size_t(w) * std::size_t(h), 1);
    if (radius <= 0) return keep;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
            bool uniform = true;
            for (int dy = -radius; dy <= radius && uniform; ++dy)
                for (int dx = -radius; dx <= radius && uniform; ++dx) {
                    const int xx = std::clamp(x + dx, 0, w - 1), yy = std::clamp(y + dy, 0, h - 1);
                    const std::size_t j = std::size_t(yy) * std::size_t(w) + std::size_t(xx);
                    for (const auto* m : {&ma, &mb})
                        if (!m->empty() && (*m)[j] != (*m)[i]) uniform = false;
                }
            keep[i] = uniform;
        }
    return keep;
}

void finish_stats(ChannelStats& s, double sum, double sum_sq) {
    s.mean_error = s.count ? sum / double(s.count) : 0.0;
    s.rms_error = s.count ? std::sqrt(sum_sq / double(s.count)) : 0.0;
    s.psnr = s.rms_error > 0 ? 20.0 * std::log10(1.0 / s.rms_error) : std::numeric_limits<double>::infinity();
}

// Running sums for one ChannelStats.
struct Accumulator {
    double sum = 0, sum_sq = 0;
    void add(ChannelStats& s, double e, int x, int y) {
        sum += e;
        sum_sq += e * e;
        ++s.count;
        if (e > s.max_error) {
            s.max_error = e;
            s.max_x = x;
            s.max_y = y;
        }
    }
    void merge(ChannelStats& into, Accumulator& acc, const ChannelStats& from) const {
        acc.sum += sum;
        acc.sum_sq += sum_sq;
        into.count += from.count;
        if (from.max_error > into.max_error) {
            into.max_error = from.max_error;
            into.max_x = from.max_x;
            into.max_y = from.max_y;
        }
        if (from.nonfinite && (!into.nonfinite || std::pair(from.nonfinite_y, from.nonfinite_x) <
                                                      std::pair(into.nonfinite_y, into.nonfinite_x))) {
            into.nonfinite_x = from.nonfinite_x;
            into.nonfinite_y = from.nonfinite_y;
        }
        into.nonfinite += from.nonfinite;
    }
};

void check_finite_nonnegative(double v, const char* name) {
    if (!std::isfinite(v) || v < 0) throw_error("--{} must be a finite number >= 0, got {}", name, v);
}

}  // namespace

void validate_compare_options(const CompareOptions& o) {
    check_finite_nonnegative(o.fail, "fail");
    check_finite_nonnegative(o.failpercent, "failpercent");
    if (o.failpercent > 100) throw_error("--failpercent must be in [0, 100], got {}", o.failpercent);
    if (std::isnan(o.hardfail) || o.hardfail < 0)
        throw_error("--hardfail must be a number >= 0 (inf for none), got {}", o.hardfail);
    if (o.erode_mask < 0) throw_error("--erode-mask must be >= 0, got {}", o.erode_mask);
}

CompareResult compare_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                             const CompareOptions& options, const std::string& a_name,
                             const std::string& b_name) {
    validate_compare_options(options);
    const std::vector<ChannelRef> ca = channels_of(a), cb = channels_of(b);
    if (ca.empty()) throw_error("{}: no channels", a_name);
    if (cb.empty()) throw_error("{}: no channels", b_name);
    CompareResult r;
    r.width = ca.front().image->width();
    r.height = ca.front().image->height();
    for (const auto* list : {&ca, &cb})
        for (const ChannelRef& c : *list)
            if (c.image->width() != r.width || c.image->height() != r.height)
                throw_error("{} and {} differ in size", a_name, b_name);
    std::size_t ia = 0, ib = 0;
    while (ia < ca.size() || ib < cb.size()) {
        if (ib == cb.size() || (ia < ca.size() && ca[ia].name < cb[ib].name))
            throw_error("channel '{}' is in {} but not in {}", ca[ia].name, a_name, b_name);
        if (ia == ca.size() || cb[ib].name < ca[ia].name)
            throw_error("channel '{}' is in {} but not in {}", cb[ib].name, b_name, a_name);
        ++ia;
        ++ib;
    }
    const std::vector<std::uint8_t> ma = hard_mask(a), mb = hard_mask(b);
    if (options.erode_mask > 0 && ma.empty() && mb.empty())
        throw_error("--erode-mask needs a 'mask' layer in {} or {}", a_name, b_name);
    const std::vector<std::uint8_t> keep = interior_pixels(ma, mb, r.width, r.height, options.erode_mask);

    // Layer of each channel (by a's layers, which own the sorted channels).
    std::vector<std::string> layer_names;
    for (const ExrLayer& layer : a) layer_names.push_back(layer.name);
    auto layer_of = [&](const ChannelRef& c) {
        for (std::size_t k = 0; k < a.size(); ++k)
            if (&a[k].image == c.image) return k;
        return std::size_t(0);
    };

    const std::size_t n = std::size_t(r.width) * std::size_t(r.height);
    std::vector<std::uint8_t> failed(n, 0);
    std::vector<std::vector<std::uint8_t>> layer_failed(a.size(), std::vector<std::uint8_t>(n, 0));
    r.layers.resize(a.size());
    std::vector<Accumulator> layer_acc(a.size());
    Accumulator all_acc;
    r.overall.name = "all";
    for (std::size_t k = 0; k < ca.size(); ++k) {
        ChannelStats s;
        s.name = ca[k].name;
        Accumulator acc;
        const Image& ima = *ca[k].image;
        const Image& imb = *cb[k].image;
        const std::size_t layer = layer_of(ca[k]);
        for (std::size_t i = 0; i < n; ++i) {
            if (!keep[i]) continue;
            const int x = int(i % std::size_t(r.width)), y = int(i / std::size_t(r.width));
            const double va = ima.at(x, y, ca[k].channel), vb = imb.at(x, y, cb[k].channel);
            bool fails;
            if (std::isfinite(va) && std::isfinite(vb)) {
                const double e = std::fabs(va - vb);
                acc.add(s, e, x, y);
                fails = e > options.fail;
            } else if (options.allow_nonfinite && ((std::isnan(va) && std::isnan(vb)) || va == vb)) {
                acc.add(s, 0.0, x, y);  // NaN = NaN, +inf = +inf: allowed as equal
                fails = false;
            } else {
                if (!s.nonfinite) s.nonfinite_x = x, s.nonfinite_y = y;
                ++s.nonfinite;
                fails = true;
            }
            if (fails) failed[i] = layer_failed[layer][i] = 1;
        }
        finish_stats(s, acc.sum, acc.sum_sq);
        acc.merge(r.overall, all_acc, s);
        acc.merge(r.layers[layer].stats, layer_acc[layer], s);
        r.channels.push_back(s);
    }
    finish_stats(r.overall, all_acc.sum, all_acc.sum_sq);
    for (std::size_t i = 0; i < n; ++i) {
        r.compared_pixels += keep[i];
        r.failed_pixels += failed[i];
    }
    auto percent = [&](std::size_t count) {
        return r.compared_pixels ? 100.0 * double(count) / double(r.compared_pixels) : 0.0;
    };
    auto passes = [&](double fail_percent, const ChannelStats& s) {
        return fail_percent <= options.failpercent && s.max_error <= options.hardfail && s.nonfinite == 0;
    };
    for (std::size_t k = 0; k < a.size(); ++k) {
        LayerResult& l = r.layers[k];
        l.name = a[k].name;
        l.stats.name = a[k].name;
        finish_stats(l.stats, layer_acc[k].sum, layer_acc[k].sum_sq);
        for (std::size_t i = 0; i < n; ++i) l.failed_pixels += layer_failed[k][i];
        l.fail_percent = percent(l.failed_pixels);
        l.passed = passes(l.fail_percent, l.stats);
    }
    r.fail_percent = percent(r.failed_pixels);
    r.passed = passes(r.fail_percent, r.overall);
    return r;
}

std::vector<ExrLayer> read_comparable_image(const std::string& path) {
    if (lower_extension(path) == ".exr") return read_exr_layers(path);
    Image image = read_image(path);
    static const std::vector<std::vector<std::string>> names = {
        {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
    if (image.channels() < 1 || image.channels() > 4)
        throw_error("{}: {} channels (1 to 4 expected)", path, image.channels());
    return {{"", names[std::size_t(image.channels() - 1)], std::move(image)}};
}

std::vector<ExrLayer> difference_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b,
                                        float scale) {
    std::vector<ExrLayer> out;
    for (const ExrLayer& la : a) {
        const auto it =
            std::find_if(b.begin(), b.end(), [&](const ExrLayer& lb) { return lb.name == la.name; });
        ExrLayer d = la;
        for (float& v : d.image.values()) v = 0.f;
        if (it != b.end() && it->image.values().size() == la.image.values().size()) {
            for (int c = 0; c < la.image.channels(); ++c) {
                // Match channels by name: the file order may differ.
                const auto cit = std::find(
                    it->channel_names.begin(), it->channel_names.end(), la.channel_names[std::size_t(c)]);
                if (cit == it->channel_names.end()) continue;
                const int cb = int(cit - it->channel_names.begin());
                for (std::size_t i = 0; i < la.image.pixel_count(); ++i) {
                    const int x = int(i % std::size_t(la.image.width())),
                              y = int(i / std::size_t(la.image.width()));
                    d.image.at(x, y, c) = std::fabs(la.image.at(x, y, c) - it->image.at(x, y, cb)) * scale;
                }
            }
        }
        out.push_back(std::move(d));
    }
    return out;
}

}  // namespace tdf
