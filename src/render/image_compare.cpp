#include <tdf/render/image_compare.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cmath>

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
    std::sort(out.begin(), out.end(), [](const ChannelRef& x, const ChannelRef& y) { return x.name < y.name; });
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
std::vector<std::uint8_t> interior_pixels(const std::vector<std::uint8_t>& ma, const std::vector<std::uint8_t>& mb,
                                          int w, int h, int radius) {
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

void finish_stats(ChannelStats& s, double sum, double sum_sq, std::size_t count) {
    s.mean_error = count ? sum / double(count) : 0.0;
    s.rms_error = count ? std::sqrt(sum_sq / double(count)) : 0.0;
    s.psnr = s.rms_error > 0 ? 20.0 * std::log10(1.0 / s.rms_error) : std::numeric_limits<double>::infinity();
}

}  // namespace

CompareResult compare_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b, const CompareOptions& options,
                             const std::string& a_name, const std::string& b_name) {
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

    const std::size_t n = std::size_t(r.width) * std::size_t(r.height);
    std::vector<std::uint8_t> failed(n, 0);
    double all_sum = 0, all_sq = 0;
    std::size_t all_count = 0;
    r.overall.name = "all";
    for (std::size_t k = 0; k < ca.size(); ++k) {
        ChannelStats s;
        s.name = ca[k].name;
        double sum = 0, sq = 0;
        std::size_t count = 0;
        const Image& ima = *ca[k].image;
        const Image& imb = *cb[k].image;
        for (std::size_t i = 0; i < n; ++i) {
            if (!keep[i]) continue;
            const int x = int(i % std::size_t(r.width)), y = int(i / std::size_t(r.width));
            const double va = ima.at(x, y, ca[k].channel), vb = imb.at(x, y, cb[k].channel);
            // NaN in one image and not the other is an infinite error.
            double e = std::fabs(va - vb);
            if (std::isnan(va) != std::isnan(vb)) e = std::numeric_limits<double>::infinity();
            if (std::isnan(e)) e = 0;  // both NaN, or equal infinities
            sum += e;
            sq += e * e;
            ++count;
            if (e > s.max_error) {
                s.max_error = e;
                s.max_x = x;
                s.max_y = y;
            }
            if (e > options.fail) failed[i] = 1;
        }
        finish_stats(s, sum, sq, count);
        all_sum += sum;
        all_sq += sq;
        all_count += count;
        if (s.max_error > r.overall.max_error) {
            r.overall.max_error = s.max_error;
            r.overall.max_x = s.max_x;
            r.overall.max_y = s.max_y;
        }
        r.channels.push_back(s);
    }
    finish_stats(r.overall, all_sum, all_sq, all_count);
    for (std::size_t i = 0; i < n; ++i) {
        r.compared_pixels += keep[i];
        r.failed_pixels += failed[i];
    }
    r.fail_percent = r.compared_pixels ? 100.0 * double(r.failed_pixels) / double(r.compared_pixels) : 0.0;
    r.passed = r.fail_percent <= options.failpercent && r.overall.max_error <= options.hardfail;
    return r;
}

std::vector<ExrLayer> difference_layers(const std::vector<ExrLayer>& a, const std::vector<ExrLayer>& b, float scale) {
    std::vector<ExrLayer> out;
    for (const ExrLayer& la : a) {
        const auto it = std::find_if(b.begin(), b.end(), [&](const ExrLayer& lb) { return lb.name == la.name; });
        ExrLayer d = la;
        for (float& v : d.image.values()) v = 0.f;
        if (it != b.end() && it->image.values().size() == la.image.values().size()) {
            for (int c = 0; c < la.image.channels(); ++c) {
                // Match channels by name: the file order may differ.
                const auto cit = std::find(it->channel_names.begin(), it->channel_names.end(),
                                           la.channel_names[std::size_t(c)]);
                if (cit == it->channel_names.end()) continue;
                const int cb = int(cit - it->channel_names.begin());
                for (std::size_t i = 0; i < la.image.pixel_count(); ++i) {
                    const int x = int(i % std::size_t(la.image.width())), y = int(i / std::size_t(la.image.width()));
                    d.image.at(x, y, c) = std::fabs(la.image.at(x, y, c) - it->image.at(x, y, cb)) * scale;
                }
            }
        }
        out.push_back(std::move(d));
    }
    return out;
}

}  // namespace tdf
