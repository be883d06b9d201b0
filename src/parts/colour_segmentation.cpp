// Colour clustering for the `colour` parts source. Lloyd's k-means on a deterministic subsample
// (the update is serial and cheap; the assignment of every sample is parallel and independent,
// so results do not depend on the thread count).
#include <tdf/parts/colour_segmentation.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_set>

namespace tdf {

namespace {

float linear_from_srgb(float c) {
    c = std::clamp(c, 0.f, 1.f);
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float lab_f(float t) {
    constexpr float kDelta = 6.f / 29.f;
    return t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3.f * kDelta * kDelta) + 4.f / 29.f;
}

float distance2(Vec3f a, Vec3f b) { return length_squared(a - b); }

int nearest(const std::vector<Vec3f>& centres, Vec3f p) {
    int best = 0;
    float best_d = std::numeric_limits<float>::max();
    for (int c = 0; c < int(centres.size()); ++c) {
        const float d = distance2(centres[std::size_t(c)], p);
        if (d < best_d) {
            best_d = d;
            best = c;
        }
    }
    return best;
}

struct KMeansResult {
    std::vector<Vec3f> centres;
    double inertia = 0;
};

// Weighted k-means with k-means++ seeding on `points`.
KMeansResult kmeans(const std::vector<Vec3f>& points, const std::vector<float>& weight, int k, int iterations,
                    std::uint64_t seed) {
    Rng rng = Rng::stream(seed, std::uint64_t(k));
    const std::size_t n = points.size();
    std::vector<Vec3f> centres;
    std::vector<double> d2(n, std::numeric_limits<double>::max());
    auto pick = [&](const std::vector<double>& w) {
        const double total = std::accumulate(w.begin(), w.end(), 0.0);
        if (!(total > 0)) return std::size_t(rng.uniform_int(0, int(n)));
        double r = double(rng.uniform()) * total;
        for (std::size_t i = 0; i < n; ++i) {
            r -= w[i];
            if (r <= 0) return i;
        }
        return n - 1;
    };
    std::vector<double> w0(weight.begin(), weight.end());
    centres.push_back(points[pick(w0)]);
    while (int(centres.size()) < k) {
        std::vector<double> w(n);
        for (std::size_t i = 0; i < n; ++i) {
            d2[i] = std::min(d2[i], double(distance2(points[i], centres.back())));
            w[i] = d2[i] * double(weight[i]);
        }
        centres.push_back(points[pick(w)]);
    }
    std::vector<int> label(n, -1);
    for (int it = 0; it < iterations; ++it) {
        bool changed = false;
        for (std::size_t i = 0; i < n; ++i) {
            const int c = nearest(centres, points[i]);
            changed |= c != label[i];
            label[i] = c;
        }
        std::vector<double> sum(std::size_t(k) * 3, 0.0), mass(std::size_t(k), 0.0);
        for (std::size_t i = 0; i < n; ++i) {
            const auto c = std::size_t(label[i]);
            for (int a = 0; a < 3; ++a) sum[c * 3 + std::size_t(a)] += double(points[i][a]) * weight[i];
            mass[c] += weight[i];
        }
        for (std::size_t c = 0; c < std::size_t(k); ++c) {
            if (mass[c] > 0) {
                centres[c] = {float(sum[c * 3] / mass[c]),
                              float(sum[c * 3 + 1] / mass[c]),
                              float(sum[c * 3 + 2] / mass[c])};
            } else {
                // Empty cluster: restart it at the point farthest from its centre.
                std::size_t far = 0;
                float far_d = -1;
                for (std::size_t i = 0; i < n; ++i) {
                    const float d = distance2(points[i], centres[std::size_t(label[i])]);
                    if (d > far_d) {
                        far_d = d;
                        far = i;
                    }
                }
                centres[c] = points[far];
                changed = true;
            }
        }
        if (!changed && it > 0) break;
    }
    KMeansResult r;
    r.centres = centres;
    for (std::size_t i = 0; i < n; ++i)
        r.inertia +=
            double(weight[i]) * distance2(points[i], centres[std::size_t(nearest(centres, points[i]))]);
    return r;
}

// Mean silhouette of the labelling of `points` by nearest centre (Rousseeuw 1987).
double mean_silhouette(const std::vector<Vec3f>& points, const std::vector<Vec3f>& centres) {
    const std::size_t n = points.size();
    const std::size_t k = centres.size();
    std::vector<int> label(n);
    std::vector<int> count(k, 0);
    for (std::size_t i = 0; i < n; ++i) {
        label[i] = nearest(centres, points[i]);
        ++count[std::size_t(label[i])];
    }
    double total = 0;
    std::vector<double> sum(k);
    for (std::size_t i = 0; i < n; ++i) {
        std::fill(sum.begin(), sum.end(), 0.0);
        for (std::size_t j = 0; j < n; ++j)
            sum[std::size_t(label[j])] += std::sqrt(double(distance2(points[i], points[j])));
        const auto own = std::size_t(label[i]);
        if (count[own] <= 1) continue;  // silhouette 0 for singletons
        const double a = sum[own] / double(count[own] - 1);
        double b = std::numeric_limits<double>::max();
        for (std::size_t c = 0; c < k; ++c)
            if (c != own && count[c] > 0) b = std::min(b, sum[c] / double(count[c]));
        if (b == std::numeric_limits<double>::max()) continue;
        const double m = std::max(a, b);
        total += m > 0 ? (b - a) / m : 0.0;
    }
    return total / double(n);
}

}  // namespace

Vec3f srgb_to_lab(Vec3f rgb) {
    const float r = linear_from_srgb(rgb.x), g = linear_from_srgb(rgb.y), b = linear_from_srgb(rgb.z);
    // sRGB (D65) to XYZ, normalised by the D65 white.
    const float x = (0.4124564f * r + 0.3575761f * g + 0.1804375f * b) / 0.95047f;
    const float y = 0.2126729f * r + 0.7151522f * g + 0.0721750f * b;
    const float z = (0.0193339f * r + 0.1191920f * g + 0.9503041f * b) / 1.08883f;
    const float fx = lab_f(x), fy = lab_f(y), fz = lab_f(z);
    return {116.f * fy - 16.f, 500.f * (fx - fy), 200.f * (fy - fz)};
}

ColourClustering cluster_colours(const std::vector<Vec3f>& rgb, const std::vector<float>& weight,
                                 const ColourClusteringOptions& options, const std::string& where) {
    if (rgb.size() != weight.size())
        throw_error("{}: {} colours but {} weights", where, rgb.size(), weight.size());
    if (options.k_max < 2 || options.k_max > 16)
        throw_error("{}: k_max must be in [2, 16], got {}", where, options.k_max);
    if (options.k == 1 || options.k < 0 || options.k > 16)
        throw_error("{}: k must be 0 (choose) or in [2, 16], got {}", where, options.k);
    ColourClustering out;
    {
        std::unordered_set<std::uint32_t> seen;
        for (const Vec3f& c : rgb) {
            std::uint32_t key = 0;
            for (int a = 0; a < 3; ++a)
                key = key * 256u + std::uint32_t(std::lround(std::clamp(c[a], 0.f, 1.f) * 255.f));
            seen.insert(key);
        }
        out.distinct_colours = int(seen.size());
    }
    if (rgb.empty()) throw_error("{}: no surface texels to segment", where);
    if (options.k > out.distinct_colours)
        throw_error("{}: k is {} but the albedo has only {} distinct colour(s)",
                    where,
                    options.k,
                    out.distinct_colours);
    if (out.distinct_colours < 2)
        throw_error(
            "{}: the albedo has a single colour; colour segmentation needs at least 2 (use another parts "
            "source)",
            where);

    std::vector<Vec3f> lab(rgb.size());
    parallel_for(rgb.size(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) lab[i] = srgb_to_lab(rgb[i]);
    });
    // Deterministic, evenly spread subsample for the fits.
    const std::size_t n = rgb.size();
    const std::size_t m = std::min(n, std::size_t(std::max(options.sample_limit, 100)));
    std::vector<Vec3f> sample(m);
    std::vector<float> sample_weight(m);
    for (std::size_t j = 0; j < m; ++j) {
        const std::size_t i = j * n / m;
        sample[j] = lab[i];
        sample_weight[j] = weight[i];
    }

    std::vector<Vec3f> centres;
    if (options.k >= 2) {
        centres = kmeans(sample, sample_weight, options.k, options.iterations, options.seed).centres;
    } else {
        const std::size_t s = std::min(m, std::size_t(std::max(options.silhouette_samples, 10)));
        std::vector<Vec3f> probe(s);
        for (std::size_t j = 0; j < s; ++j) probe[j] = sample[j * m / s];
        double best = -2;
        const int top = std::min(options.k_max, out.distinct_colours);
        for (int k = 2; k <= top; ++k) {
            std::vector<Vec3f> c = kmeans(sample, sample_weight, k, options.iterations, options.seed).centres;
            const double score = mean_silhouette(probe, c);
            out.silhouette.push_back(score);
            if (score > best + 1e-9) {
                best = score;
                centres = std::move(c);
            }
        }
    }

    const std::size_t k = centres.size();
    std::vector<int> raw(n);
    parallel_for(n, 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) raw[i] = nearest(centres, lab[i]);
    });
    std::vector<double> mass(k, 0.0), lab_sum(k * 3, 0.0), rgb_sum(k * 3, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        const auto c = std::size_t(raw[i]);
        mass[c] += weight[i];
        for (int a = 0; a < 3; ++a) {
            lab_sum[c * 3 + std::size_t(a)] += double(lab[i][a]) * weight[i];
            rgb_sum[c * 3 + std::size_t(a)] += double(rgb[i][a]) * weight[i];
        }
    }
    std::vector<std::size_t> order(k);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(
        order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return mass[a] > mass[b]; });
    std::vector<int> rank(k);
    for (std::size_t r = 0; r < k; ++r) {
        const std::size_t c = order[r];
        rank[c] = int(r);
        ColourCluster cl;
        const double w = mass[c] > 0 ? mass[c] : 1.0;
        cl.lab = {float(lab_sum[c * 3] / w), float(lab_sum[c * 3 + 1] / w), float(lab_sum[c * 3 + 2] / w)};
        cl.rgb = {float(rgb_sum[c * 3] / w), float(rgb_sum[c * 3 + 1] / w), float(rgb_sum[c * 3 + 2] / w)};
        cl.weight = mass[c];
        out.clusters.push_back(cl);
    }
    out.label.resize(n);
    for (std::size_t i = 0; i < n; ++i) out.label[i] = rank[std::size_t(raw[i])];
    return out;
}

void majority_smooth(std::vector<int>& label,
                     const std::vector<std::vector<std::pair<int, float>>>& neighbours, int rounds,
                     float self_weight) {
    int top = 0;
    for (int l : label) top = std::max(top, l + 1);
    for (int round = 0; round < rounds; ++round) {
        std::vector<int> next(label.size());
        std::atomic<bool> changed{false};
        parallel_for(label.size(), 2048, [&](std::size_t begin, std::size_t end) {
            std::vector<float> votes(static_cast<std::size_t>(top));
            for (std::size_t i = begin; i < end; ++i) {
                next[i] = label[i];
                if (label[i] < 0) continue;
                std::fill(votes.begin(), votes.end(), 0.f);
                votes[std::size_t(label[i])] += self_weight;
                for (const auto& [j, w] : neighbours[i])
                    if (label[std::size_t(j)] >= 0) votes[std::size_t(label[std::size_t(j)])] += w;
                int best = label[i];
                for (int l = 0; l < top; ++l)
                    if (votes[std::size_t(l)] > votes[std::size_t(best)]) best = l;
                if (best != label[i]) {
                    next[i] = best;
                    changed = true;
                }
            }
        });
        label.swap(next);
        if (!changed) break;
    }
}

}  // namespace tdf
