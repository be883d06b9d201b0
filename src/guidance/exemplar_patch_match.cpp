#include <tdf/guidance/exemplar_patch_match.h>

#include <tdf/tactile/tactile_map.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/core/image_ops.h>
#include <tdf/io/image_io.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace tdf {

/// One searchable version of an exemplar (a rotation, optionally row-flipped), as a pyramid:
/// levels[0] is the finest. 3 channels, unit vectors.
struct ExemplarPatchMatchBackend::Variant {
    std::vector<Image> levels;
};

namespace {

using Variant = ExemplarPatchMatchBackend::Variant;

/// A nearest-neighbour field entry: the centre (x, y) of the matched patch in variant v, and the
/// patch distance.
struct Match {
    int v = 0;
    int x = 0;
    int y = 0;
    float d = std::numeric_limits<float>::infinity();
};

void normalize_vectors(Image& image) {
    float* p = image.data();
    for (std::size_t i = 0; i < image.pixel_count(); ++i, p += 3) {
        const Vec3f n = safe_normalize(Vec3f(p[0], p[1], p[2]));
        p[0] = n.x, p[1] = n.y, p[2] = n.z;
    }
}

/// Rotates a normal map by `angle` counter-clockwise (y up): the picture and the (x, y)
/// components of its vectors. Multiples of 90 degrees are exact index permutations (sampling
/// lands on pixel centres); other angles are resampled bilinearly and cropped to the largest
/// axis-aligned square inside the rotated picture. With `mirrored` the source is read as
/// the map mirrored across the horizontal axis (rows reversed, y negated; both exact), which is
/// how a tangent-space map appears on a chart of handedness -1 (the bitangent is flipped).
Image rotate_normal_map(const Image& source, float angle, bool mirrored = false) {
    const float c = std::cos(angle), s = std::sin(angle);
    const int quarter = int(std::lround(angle / (0.5f * kPi)));
    const bool exact = std::abs(angle - float(quarter) * 0.5f * kPi) < 1e-6f;
    const int sw = source.width(), sh = source.height();
    int width = sw, height = sh;
    if (exact && (quarter & 1)) std::swap(width, height);
    if (!exact) width = height = int(float(std::min(sw, sh)) / (std::abs(c) + std::abs(s)));
    const float cx_src = 0.5f * float(sw - 1), cy_src = 0.5f * float(sh - 1);
    const float cx = 0.5f * float(width - 1), cy = 0.5f * float(height - 1);
    const auto row = [&](int y) {
        return source.data() + std::size_t(mirrored ? sh - 1 - y : y) * std::size_t(sw) * 3;
    };
    const float flip = mirrored ? -1.0f : 1.0f;
    Image out(width, height, 3);
    // Tiles, so the source pixels a tile reads (a turned square) stay in the L1 cache.
    parallel_for_tiles(width, height, 32, [&](int x_begin, int y_begin, int x_end, int y_end) {
        for (int y = y_begin; y < y_end; ++y) {
            const float v = cy - float(y);
            const float sv = s * v, cv = c * v;
            float* dst = out.pixel(x_begin, y);
            for (int x = x_begin; x < x_end; ++x, dst += 3) {
                // y-up offsets from the centre, rotated back by -angle into the source.
                const float u = float(x) - cx;
                float sx = c * u + sv + cx_src;
                float sy = cy_src - (-s * u + cv);
                if (exact) sx = std::round(sx), sy = std::round(sy);
                sx = std::clamp(sx, 0.0f, float(sw - 1));
                sy = std::clamp(sy, 0.0f, float(sh - 1));
                const int x0 = int(sx), y0 = int(sy);
                const int x1 = std::min(x0 + 1, sw - 1), y1 = std::min(y0 + 1, sh - 1);
                const float tx = sx - float(x0), ty = sy - float(y0);
                const float* r0 = row(y0);
                const float* r1 = row(y1);
                const float* p00 = r0 + 3 * x0;
                const float* p10 = r0 + 3 * x1;
                const float* p01 = r1 + 3 * x0;
                const float* p11 = r1 + 3 * x1;
                float n[3];
                for (int ch = 0; ch < 3; ++ch) {
                    // y components of a mirrored source are read negated (an exact sign flip).
                    const float f = ch == 1 ? flip : 1.0f;
                    n[ch] = ((f * p00[ch]) * (1 - tx) + (f * p10[ch]) * tx) * (1 - ty) +
                            ((f * p01[ch]) * (1 - tx) + (f * p11[ch]) * tx) * ty;
                }
                const Vec3f r = safe_normalize(Vec3f(c * n[0] - s * n[1], s * n[0] + c * n[1], n[2]));
                dst[0] = r.x, dst[1] = r.y, dst[2] = r.z;
            }
        }
    });
    return out;
}

/// Rows reversed, vectors unchanged: what the reference's patch renders do (spec 13.13).
Image flip_rows(const Image& image) {
    Image out(image.width(), image.height(), image.channels());
    const std::size_t row = std::size_t(image.width()) * std::size_t(image.channels());
    for (int y = 0; y < image.height(); ++y)
        std::copy_n(image.pixel(0, image.height() - 1 - y), row, out.pixel(0, y));
    return out;
}

/// Coverage-weighted 2x downsampling: the average of m * n divided by the average of m, so
/// background zeros do not shrink the normals at the silhouette.
void downsample_weighted(const Image& normals, const Image& mask, Image& normals_out, Image& mask_out) {
    Image weighted = normals;
    for (std::size_t p = 0; p < normals.pixel_count(); ++p)
        for (int c = 0; c < 3; ++c) weighted.data()[3 * p + std::size_t(c)] *= mask.data()[p];
    normals_out = downsample_half(weighted);
    mask_out = downsample_half(mask);
    for (std::size_t p = 0; p < mask_out.pixel_count(); ++p) {
        const float m = mask_out.data()[p];
        float* n = normals_out.data() + 3 * p;
        for (int c = 0; c < 3; ++c) n[c] = m > 0.0f ? n[c] / m : 0.0f;
    }
}

/// The search and voting state of one image at one pyramid level.
class LevelSolver {
public:
    LevelSolver(const Image& target, const Image& mask, const std::vector<Variant>& variants, int level,
                int patch_size)
        : m_target(target),
          m_mask(mask),
          m_variants(variants),
          m_level(level),
          m_radius(patch_size / 2),
          m_width(target.width()),
          m_height(target.height()) {
        // A pixel's patch takes part (kActive) when its window touches the foreground; kFull
        // marks windows inside the image and fully covered, which take the fast distance path.
        m_active.assign(std::size_t(m_width) * std::size_t(m_height), kInactive);
        for (int y = 0; y < m_height; ++y)
            for (int x = 0; x < m_width; ++x) {
                if (m_mask.at(x, y, 0) <= 0.0f) continue;
                for (int dy = -m_radius; dy <= m_radius; ++dy)
                    for (int dx = -m_radius; dx <= m_radius; ++dx) {
                        const int qx = x + dx, qy = y + dy;
                        if (qx >= 0 && qy >= 0 && qx < m_width && qy < m_height)
                            m_active[index(qx, qy)] = kActive;
                    }
            }
        for (int y = m_radius; y < m_height - m_radius; ++y)
            for (int x = m_radius; x < m_width - m_radius; ++x) {
                bool full = true;
                for (int dy = -m_radius; dy <= m_radius && full; ++dy)
                    for (int dx = -m_radius; dx <= m_radius && full; ++dx)
                        full = m_mask.at(x + dx, y + dy, 0) >= 1.0f;
                if (full) m_active[index(x, y)] = kFull;
            }
    }

    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(m_width) + std::size_t(x); }
    bool active(int x, int y) const { return m_active[index(x, y)] != 0; }
    const Image& exemplar(int v) const { return m_variants[std::size_t(v)].levels[std::size_t(m_level)]; }

    /// Clamps a patch centre into the valid range of variant v.
    void clamp_centre(Match& m) const {
        const Image& e = exemplar(m.v);
        m.x = std::clamp(m.x, m_radius, e.width() - 1 - m_radius);
        m.y = std::clamp(m.y, m_radius, e.height() - 1 - m_radius);
    }

    /// Mask-weighted SSD between the target patch at (x, y) and the exemplar patch of `m`;
    /// stops early once it exceeds `bound`.
    float distance(int x, int y, const Match& m, float bound) const {
        const Image& e = exemplar(m.v);
        if (m_active[index(x, y)] == kFull) return distance_full(x, y, e, m, bound);
        float sum = 0.0f;
        for (int dy = -m_radius; dy <= m_radius; ++dy) {
            const int ty = y + dy;
            if (ty < 0 || ty >= m_height) continue;
            for (int dx = -m_radius; dx <= m_radius; ++dx) {
                const int tx = x + dx;
                if (tx < 0 || tx >= m_width) continue;
                const float w = m_mask.at(tx, ty, 0);
                if (w <= 0.0f) continue;
                const float* a = m_target.pixel(tx, ty);
                const float* b = e.pixel(m.x + dx, m.y + dy);
                const float d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
                sum += w * (d0 * d0 + d1 * d1 + d2 * d2);
            }
            if (sum > bound) return sum;
        }
        return sum;
    }

    /// distance() for a window inside the image with weight 1 everywhere: each window row is one
    /// contiguous run of 3 * patch floats in both images. Four partial sums let the compiler
    /// vectorise without reassociating.
    float distance_full(int x, int y, const Image& e, const Match& m, float bound) const {
        const int n = 3 * (2 * m_radius + 1);
        float sum = 0.0f;
        for (int dy = -m_radius; dy <= m_radius; ++dy) {
            const float* a = m_target.pixel(x - m_radius, y + dy);
            const float* b = e.pixel(m.x - m_radius, m.y + dy);
            float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f};
            int i = 0;
            for (; i + 4 <= n; i += 4)
                for (int k = 0; k < 4; ++k) {
                    const float d = a[i + k] - b[i + k];
                    acc[k] += d * d;
                }
            for (; i < n; ++i) {
                const float d = a[i] - b[i];
                acc[0] += d * d;
            }
            sum += (acc[0] + acc[1]) + (acc[2] + acc[3]);
            if (sum > bound) return sum;
        }
        return sum;
    }

    Match random_match(Rng& rng) const {
        Match m;
        m.v = rng.uniform_int(0, int(m_variants.size()));
        const Image& e = exemplar(m.v);
        m.x = rng.uniform_int(m_radius, e.width() - m_radius);
        m.y = rng.uniform_int(m_radius, e.height() - m_radius);
        return m;
    }

    void try_candidate(int x, int y, Match candidate, Match& best) const {
        clamp_centre(candidate);
        if (candidate.v == best.v && candidate.x == best.x && candidate.y == best.y) return;
        candidate.d = distance(x, y, candidate, best.d);
        if (candidate.d < best.d) best = candidate;
    }

    /// Random initialisation of the field (coarsest level).
    std::vector<Match> random_field(std::uint64_t seed) const {
        std::vector<Match> field(m_active.size());
        parallel_for(std::size_t(m_height), 4, [&](std::size_t y0, std::size_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < m_width; ++x) {
                    if (!active(x, y)) continue;
                    Rng rng = Rng::stream(seed, index(x, y));
                    Match& m = field[index(x, y)];
                    m = random_match(rng);
                    m.d = distance(x, y, m, std::numeric_limits<float>::infinity());
                }
        });
        return field;
    }

    /// The coarser level's field, upsampled (each coarse match covers 2x2 fine pixels).
    std::vector<Match> upsampled_field(const std::vector<Match>& coarse, int coarse_width, int coarse_height,
                                       std::uint64_t seed) const {
        std::vector<Match> field(m_active.size());
        parallel_for(std::size_t(m_height), 4, [&](std::size_t y0, std::size_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < m_width; ++x) {
                    if (!active(x, y)) continue;
                    const int cx = std::min(x / 2, coarse_width - 1), cy = std::min(y / 2, coarse_height - 1);
                    Match m = coarse[std::size_t(cy) * std::size_t(coarse_width) + std::size_t(cx)];
                    if (!std::isfinite(m.d)) {
                        // The coarse pixel was inactive: start from a random match.
                        Rng rng = Rng::stream(seed, index(x, y));
                        m = random_match(rng);
                    } else {
                        m.x = 2 * m.x + (x & 1);
                        m.y = 2 * m.y + (y & 1);
                    }
                    clamp_centre(m);
                    m.d = distance(x, y, m, std::numeric_limits<float>::infinity());
                    field[index(x, y)] = m;
                }
        });
        return field;
    }

    /// Recomputes the distances of `field` against the current target (after a vote changed it).
    void refresh(std::vector<Match>& field) const {
        parallel_for(std::size_t(m_height), 4, [&](std::size_t y0, std::size_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < m_width; ++x) {
                    Match& m = field[index(x, y)];
                    if (active(x, y) && std::isfinite(m.d))
                        m.d = distance(x, y, m, std::numeric_limits<float>::infinity());
                }
        });
    }

    /// One PatchMatch round, Jacobi style: every pixel reads only `field` (the previous round) and
    /// writes its own entry of the result, so the result does not depend on the thread count.
    /// Propagation looks `jump` pixels away in the four directions (jump-flood schedule), then
    /// random search samples around the best match with halving radius, plus one fully random
    /// candidate that lets a pixel switch variants.
    std::vector<Match> search_round(const std::vector<Match>& field, int jump, std::uint64_t seed) const {
        std::vector<Match> next(field.size());
        parallel_for(std::size_t(m_height), 4, [&](std::size_t y0, std::size_t y1) {
            static constexpr int kDirections[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < m_width; ++x) {
                    if (!active(x, y)) continue;
                    Match best = field[index(x, y)];
                    for (const auto& dir : kDirections) {
                        const int qx = x + dir[0] * jump, qy = y + dir[1] * jump;
                        if (qx < 0 || qy < 0 || qx >= m_width || qy >= m_height || !active(qx, qy)) continue;
                        Match candidate = field[index(qx, qy)];
                        candidate.x -= dir[0] * jump;
                        candidate.y -= dir[1] * jump;
                        try_candidate(x, y, candidate, best);
                    }
                    Rng rng = Rng::stream(seed, index(x, y));
                    const Image& e = exemplar(best.v);
                    for (int radius = std::max(e.width(), e.height()); radius >= 1; radius /= 2) {
                        Match candidate = best;
                        candidate.x += rng.uniform_int(-radius, radius + 1);
                        candidate.y += rng.uniform_int(-radius, radius + 1);
                        try_candidate(x, y, candidate, best);
                    }
                    try_candidate(x, y, random_match(rng), best);
                    next[index(x, y)] = best;
                }
        });
        return next;
    }

    /// Voting: each foreground pixel becomes the unit-length average of what the matches of the
    /// patches covering it propose for it.
    Image vote(const std::vector<Match>& field) const {
        Image out = m_target;
        parallel_for(std::size_t(m_height), 4, [&](std::size_t y0, std::size_t y1) {
            for (int y = int(y0); y < int(y1); ++y)
                for (int x = 0; x < m_width; ++x) {
                    if (m_mask.at(x, y, 0) <= 0.0f) continue;
                    Vec3f sum;
                    for (int dy = -m_radius; dy <= m_radius; ++dy)
                        for (int dx = -m_radius; dx <= m_radius; ++dx) {
                            const int qx = x + dx, qy = y + dy;
                            if (qx < 0 || qy < 0 || qx >= m_width || qy >= m_height) continue;
                            const Match& m = field[index(qx, qy)];
                            if (!std::isfinite(m.d)) continue;
                            const float* e = exemplar(m.v).pixel(m.x - dx, m.y - dy);
                            sum += Vec3f(e[0], e[1], e[2]);
                        }
                    const Vec3f n = safe_normalize(sum);
                    float* dst = out.pixel(x, y);
                    dst[0] = n.x, dst[1] = n.y, dst[2] = n.z;
                }
        });
        return out;
    }

private:
    const Image& m_target;
    const Image& m_mask;
    const std::vector<Variant>& m_variants;
    int m_level;
    int m_radius;
    int m_width;
    int m_height;
    static constexpr unsigned char kInactive = 0, kActive = 1, kFull = 2;
    std::vector<unsigned char> m_active;
};

/// Sorts finite non-negative floats ascending, as std::sort does (equal values have equal bits
/// here, so the result is the same array), by a least-significant-digit radix sort of their
/// bits, which order like the values: 3 linear passes instead of N log N comparisons. Anything
/// else (negative, -0, not finite) falls back to std::sort.
void sort_non_negative(std::vector<float>& values) {
    static_assert(sizeof(float) == sizeof(std::uint32_t));
    std::uint32_t bad = 0;
    for (const float v : values) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, sizeof(bits));
        bad |= std::uint32_t(bits >= 0x7f800000u);
    }
    if (bad) {
        std::sort(values.begin(), values.end());
        return;
    }
    // Three passes of 11 bits (an odd number: the result ends in `swap`, moved back at the end).
    std::vector<float> swap(values.size());
    std::vector<float>* from = &values;
    std::vector<float>* to = &swap;
    for (const int shift : {0, 11, 22}) {
        std::vector<std::size_t> start(2049, 0);
        const auto digit = [shift](float v) {
            std::uint32_t bits;
            std::memcpy(&bits, &v, sizeof(bits));
            return (bits >> shift) & 2047u;
        };
        for (const float v : *from) ++start[digit(v) + 1];
        for (std::size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
        for (const float v : *from) (*to)[start[digit(v)]++] = v;
        std::swap(from, to);
    }
    values.swap(swap);
}

/// Sorted tilts (angle from +z, radians) of every texel of level `level` of the variants.
std::vector<float> sorted_tilts(const std::vector<Variant>& variants, std::size_t level) {
    std::vector<float> tilts;
    for (const Variant& v : variants) {
        const Image& e = v.levels[level];
        for (std::size_t p = 0; p < e.pixel_count(); ++p)
            tilts.push_back(std::acos(std::clamp(e.data()[3 * p + 2], -1.0f, 1.0f)));
    }
    sort_non_negative(tilts);
    return tilts;
}

/// Histogram matching of the relief's steepness (Kopf et al. 2007 add it to texture
/// optimization because averaging votes washes contrast out): the foreground normals are ranked
/// by tilt and each gets the exemplar's tilt at the same quantile, keeping its azimuth. The
/// image keeps where its relief is; its steepness distribution becomes the exemplar's.
void match_tilt_histogram(Image& normals, const Image& mask, const std::vector<float>& exemplar_tilts) {
    std::vector<std::pair<float, std::size_t>> order;
    for (std::size_t p = 0; p < normals.pixel_count(); ++p)
        if (mask.data()[p] > 0.0f) order.emplace_back(std::acos(std::clamp(normals.data()[3 * p + 2], -1.0f, 1.0f)), p);
    if (order.empty() || exemplar_tilts.empty()) return;
    std::sort(order.begin(), order.end());  // ties broken by pixel index: deterministic
    for (std::size_t r = 0; r < order.size(); ++r) {
        const double quantile = (double(r) + 0.5) / double(order.size());
        const float tilt = exemplar_tilts[std::min(exemplar_tilts.size() - 1, std::size_t(quantile * double(exemplar_tilts.size())))];
        float* n = normals.data() + 3 * order[r].second;
        const float xy = std::sqrt(n[0] * n[0] + n[1] * n[1]);
        const float cx = xy > 1e-6f ? n[0] / xy : 1.0f, cy = xy > 1e-6f ? n[1] / xy : 0.0f;
        n[0] = std::sin(tilt) * cx, n[1] = std::sin(tilt) * cy, n[2] = std::cos(tilt);
    }
}

/// Mixes the call's seed with the position in the algorithm into one stream seed (splitmix64).
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
    std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (1 + a * 1000003ULL + b);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// Resamples to width x height, `scale` being the size ratio: shrinking (scale < 1) is
/// prefiltered with a mask-weighted Gaussian of sigma 0.5 / scale so the coarse copy does not
/// alias.
Image resample_prefiltered(const Image& image, const Image& mask, int width, int height, float scale) {
    // Only the pixels the coarse copy reads are blurred (same numbers as blurring everything).
    return scale < 1.0f ? gaussian_blur_resized(image, mask, 0.5f / scale, width, height)
                        : resize_bilinear(image, width, height);
}

/// Resizes by `factor` (unit vectors in, unit vectors out).
Image scale_normal_map(const Image& image, float factor) {
    if (factor == 1.0f) return image;
    Image out = resample_prefiltered(image,
                                     Image(),
                                     std::max(1, int(std::lround(float(image.width()) * factor))),
                                     std::max(1, int(std::lround(float(image.height()) * factor))),
                                     factor);
    normalize_vectors(out);
    return out;
}

/// The search pyramid of one exemplar variant: levels[0] = `finest`, then box-downsampled while
/// both sides stay at least two patches wide, at most `levels` in all.
Variant build_variant(Image finest, int levels, int patch_size) {
    Variant variant;
    variant.levels.push_back(std::move(finest));
    for (int l = 1; l < levels; ++l) {
        const Image& finer = variant.levels.back();
        if (std::min(finer.width(), finer.height()) / 2 < patch_size) break;
        Image coarser = downsample_half(finer);
        normalize_vectors(coarser);
        variant.levels.push_back(std::move(coarser));
    }
    return variant;
}

/// The rotation that takes the unit vector `a` to +z by the shortest arc, applied to `v`
/// (or, with `inverse`, its transpose: +z back to `a`). Identity when `a` faces away.
Vec3f shortest_arc_to_z(Vec3f a, Vec3f v, bool inverse) {
    if (a.z <= -0.999f) return v;
    // R = I + [c]x + [c]x^2 / (1 + a.z) with c = a x z = (a.y, -a.x, 0).
    const Vec3f c(a.y, -a.x, 0.0f);
    const Vec3f cv = inverse ? cross(v, c) : cross(c, v);
    return v + cv + cross(c, cross(c, v)) / (1.0f + a.z);
}

/// How a request image is turned into the search problem: the working copy's size and the
/// magnification the exemplar gets so one texel spans as many working pixels as in the image.
struct WorkingScale {
    int width = 0;
    int height = 0;
    float exemplar_factor = 1.0f;
};

/// Exemplars are magnified at most this much: beyond it their patches are smooth ramps that
/// match anything, so the image is searched as a coarser copy instead (see the header).
constexpr float kMaxExemplarMagnification = 2.0f;

WorkingScale working_scale(float pixels_per_texel, int width, int height, int patch_size) {
    WorkingScale w{width, height, pixels_per_texel};
    if (pixels_per_texel <= kMaxExemplarMagnification) return w;
    // Shrink by d = M / max so the exemplar needs the largest allowed magnification, but keep
    // the copy at least three patches wide (or the image's size, if smaller).
    float shrink = pixels_per_texel / kMaxExemplarMagnification;
    const int short_side = std::min(width, height);
    const int min_side = std::min(short_side, 3 * patch_size);
    shrink = std::min(shrink, float(short_side) / float(min_side));
    w.width = std::max(1, int(std::lround(float(width) / shrink)));
    w.height = std::max(1, int(std::lround(float(height) / shrink)));
    w.exemplar_factor = pixels_per_texel * float(w.width) / float(width);
    return w;
}

}  // namespace

ExemplarPatchMatchBackend::Options ExemplarPatchMatchBackend::Options::from_json(const Json& config) {
    ConfigReader reader(config, "guidance backend 'exemplar_patch_match'");
    Options o;
    if (reader.has("exemplars")) {
        const Json& files = reader.raw("exemplars");
        if (!files.is_array())
            throw_error("{}: \"exemplars\" must be an array of file names", reader.where());
        for (const Json& f : files) {
            if (!f.is_string())
                throw_error("{}: \"exemplars\" must be an array of file names", reader.where());
            o.exemplar_files.push_back(f.get<std::string>());
        }
    }
    if (reader.has("exemplar_scale") && reader.raw("exemplar_scale").is_string()) {
        if (reader.raw("exemplar_scale").get<std::string>() != "auto")
            throw_error("{}: exemplar_scale must be \"auto\" or a number", reader.where());
        o.exemplar_scale = 0.0f;
    } else if (reader.has("exemplar_scale")) {
        o.exemplar_scale = reader.get<float>("exemplar_scale", o.exemplar_scale);
        if (!(o.exemplar_scale >= 0.125f && o.exemplar_scale <= 8.0f))
            throw_error("{}: exemplar_scale {} is outside [0.125, 8] (or \"auto\")", reader.where(), o.exemplar_scale);
    }
    const std::string orientation = reader.get<std::string>("orientation", "surface");
    if (orientation == "surface")
        o.orientation = Options::Orientation::Surface;
    else if (orientation == "search")
        o.orientation = Options::Orientation::Search;
    else
        throw_error("{}: orientation \"{}\" must be \"surface\" or \"search\"", reader.where(), orientation);
    o.patch_size = reader.get<int>("patch_size", o.patch_size);
    o.levels = reader.get<int>("levels", o.levels);
    o.em_iterations = reader.get<int>("em_iterations", o.em_iterations);
    o.search_iterations = reader.get<int>("search_iterations", o.search_iterations);
    o.rotations = reader.get<int>("rotations", o.rotations);
    o.flip_rows = reader.get<bool>("flip_rows", o.flip_rows);
    o.match_tilt_histogram = reader.get<bool>("match_tilt_histogram", o.match_tilt_histogram);
    reader.check_all_read();
    const std::string& where = reader.where();
    if (o.patch_size < 3 || o.patch_size > 15 || o.patch_size % 2 == 0)
        throw_error("{}: patch_size {} must be odd, 3..15", where, o.patch_size);
    if (o.levels < 1 || o.levels > 6) throw_error("{}: levels {} is outside 1..6", where, o.levels);
    if (o.em_iterations < 1 || o.em_iterations > 10)
        throw_error("{}: em_iterations {} is outside 1..10", where, o.em_iterations);
    if (o.search_iterations < 1 || o.search_iterations > 16)
        throw_error("{}: search_iterations {} is outside 1..16", where, o.search_iterations);
    if (o.rotations != 1 && o.rotations != 2 && o.rotations != 4 && o.rotations != 8)
        throw_error("{}: rotations {} must be 1, 2, 4 or 8", where, o.rotations);
    return o;
}

ExemplarPatchMatchBackend::ExemplarPatchMatchBackend(Options options) : m_options(std::move(options)) {
    if (!m_options.exemplar_files.empty()) {
        std::vector<Image> exemplars;
        for (const std::string& file : m_options.exemplar_files) exemplars.push_back(load_tactile_map(file).normals);
        set_exemplars(std::move(exemplars));
    }
}

ExemplarPatchMatchBackend::~ExemplarPatchMatchBackend() = default;

void ExemplarPatchMatchBackend::set_exemplars(std::vector<Image> tangent_normals) {
    if (tangent_normals.empty()) throw_error("guidance backend 'exemplar_patch_match': no exemplars given");
    for (std::size_t i = 0; i < tangent_normals.size(); ++i) {
        Image& exemplar = tangent_normals[i];
        if (exemplar.channels() < 3)
            throw_error("guidance backend 'exemplar_patch_match': exemplar {} has {} channels, expected 3",
                        i,
                        exemplar.channels());
        if (exemplar.channels() > 3) exemplar = exemplar.channel_range(0, 3);
        if (!exemplar.all_finite())
            throw_error("guidance backend 'exemplar_patch_match': exemplar {} has non-finite values", i);
        normalize_vectors(exemplar);
    }
    m_exemplars = std::move(tangent_normals);
    m_scaled_exemplars.clear();
    m_search_variants.clear();
    // Fail now, not at the first refinement, when the exemplars cannot hold a patch.
    search_variants(m_options.exemplar_scale > 0.0f ? m_options.exemplar_scale : 1.0f);
}

const std::vector<Image>& ExemplarPatchMatchBackend::scaled_exemplars(float factor) {
    if (factor != m_scaled_factor || m_scaled_exemplars.empty()) {
        m_scaled_exemplars.clear();
        for (const Image& exemplar : m_exemplars) m_scaled_exemplars.push_back(scale_normal_map(exemplar, factor));
        m_scaled_factor = factor;
    }
    return m_scaled_exemplars;
}

const std::vector<ExemplarPatchMatchBackend::Variant>& ExemplarPatchMatchBackend::search_variants(float factor) {
    if (factor == m_search_factor && !m_search_variants.empty()) return m_search_variants;
    std::vector<Variant> variants;
    for (const Image& exemplar : scaled_exemplars(factor)) {
        for (int r = 0; r < m_options.rotations; ++r) {
            const Image rotated = rotate_normal_map(exemplar, 2.0f * kPi * float(r) / float(m_options.rotations));
            for (int flip = 0; flip < (m_options.flip_rows ? 2 : 1); ++flip)
                variants.push_back(build_variant(flip ? flip_rows(rotated) : rotated, m_options.levels, m_options.patch_size));
        }
    }
    check_variants(variants, factor);
    m_search_tilts = tilt_tables(variants);
    m_search_variants = std::move(variants);
    m_search_factor = factor;
    return m_search_variants;
}

std::vector<std::vector<float>> ExemplarPatchMatchBackend::tilt_tables(
    const std::vector<Variant>& variants) const {
    // Per level; every variant of a set has the same number of levels (each is at least two
    // patches wide, and the rotated exemplars of a set have one size).
    std::size_t levels = variants.empty() ? 0 : variants.front().levels.size();
    for (const Variant& v : variants) levels = std::min(levels, v.levels.size());
    std::vector<std::vector<float>> tilts(levels);
    if (m_options.match_tilt_histogram)
        for (std::size_t l = 0; l < levels; ++l) tilts[l] = sorted_tilts(variants, l);
    return tilts;
}

void ExemplarPatchMatchBackend::check_variants(const std::vector<Variant>& variants, float factor) const {
    for (const Variant& v : variants) {
        const Image& finest = v.levels.front();
        if (std::min(finest.width(), finest.height()) < m_options.patch_size)
            throw_error("guidance backend 'exemplar_patch_match': an exemplar is {}x{} after scaling by {} and "
                        "rotation, smaller than a {}x{} patch",
                        finest.width(),
                        finest.height(),
                        factor,
                        m_options.patch_size,
                        m_options.patch_size);
    }
}

Image ExemplarPatchMatchBackend::synthesize(const Image& input, const Image& input_mask,
                                            const std::vector<Variant>& variants,
                                            const std::vector<std::vector<float>>& tilts, std::uint64_t seed,
                                            std::size_t item) const {
    // Levels usable by every variant and by the image (at least two patches wide).
    const int patch = m_options.patch_size;
    std::size_t levels = std::size_t(m_options.levels);
    for (const Variant& v : variants) levels = std::min(levels, v.levels.size());
    {
        int size = std::min(input.width(), input.height());
        std::size_t fit = 1;
        while (fit < levels && size / 2 >= 2 * patch) size /= 2, ++fit;
        levels = fit;
    }
    std::vector<Image> inputs{input};
    std::vector<Image> masks{input_mask};
    for (std::size_t l = 1; l < levels; ++l) {
        Image n, m;
        downsample_weighted(inputs.back(), masks.back(), n, m);
        inputs.push_back(std::move(n));
        masks.push_back(std::move(m));
    }

    std::vector<Match> field;
    Image estimate, previous_result;
    int coarse_width = 0, coarse_height = 0;
    for (std::size_t l = levels; l-- > 0;) {
        estimate = inputs[l];
        const std::uint64_t level_stage = std::uint64_t(l) * 1024;
        if (!field.empty()) {
            // Finer levels: the input plus the change the coarser level made (Laplacian
            // transfer), so the input's relief stays where it is and only its texture changes;
            // the coarser matches, carried down, start the search.
            const Image up_result = resize_bilinear(previous_result, estimate.width(), estimate.height());
            const Image up_input = resize_bilinear(inputs[l + 1], estimate.width(), estimate.height());
            for (std::size_t i = 0; i < estimate.values().size(); ++i)
                estimate.values()[i] += up_result.values()[i] - up_input.values()[i];
            normalize_vectors(estimate);
            LevelSolver solver(estimate, masks[l], variants, int(l), patch);
            field = solver.upsampled_field(field, coarse_width, coarse_height, mix_seed(seed, item, level_stage + 1023));
        }
        const std::vector<float>& exemplar_tilts = tilts[l];
        for (int em = 0; em < m_options.em_iterations; ++em) {
            if (m_options.match_tilt_histogram) match_tilt_histogram(estimate, masks[l], exemplar_tilts);
            LevelSolver solver(estimate, masks[l], variants, int(l), patch);
            // Distinct streams per (level, EM round, search round): search_iterations <= 16 < 32.
            const std::uint64_t stage = level_stage + std::uint64_t(em) * 32;
            if (field.empty())
                field = solver.random_field(mix_seed(seed, item, stage));
            else
                solver.refresh(field);
            for (int s = 0; s < m_options.search_iterations; ++s) {
                const int jump = 1 << std::max(0, m_options.search_iterations - 1 - s);
                field = solver.search_round(field, jump, mix_seed(seed, item, stage + 1 + std::uint64_t(s)));
            }
            estimate = solver.vote(field);
        }
        if (m_options.match_tilt_histogram) match_tilt_histogram(estimate, masks[l], exemplar_tilts);
        coarse_width = estimate.width();
        coarse_height = estimate.height();
        previous_result = estimate;
    }
    return estimate;
}

GuidanceResult ExemplarPatchMatchBackend::refine(const GuidanceRequest& request) {
    const std::string where = "guidance backend 'exemplar_patch_match'";
    if (request.kind != GuidanceKind::Tactile)
        throw_error(
            "{} handles tactile requests only, got a {} request", where, guidance_kind_name(request.kind));
    if (m_exemplars.empty()) throw_error("{}: no exemplars (set \"exemplars\" in its config)", where);
    validate_request(request, where);

    const bool use_surface = m_options.orientation == Options::Orientation::Surface && !request.surface_normals.empty();
    const float pixels_per_texel = m_options.exemplar_scale > 0.0f ? m_options.exemplar_scale
                                   : request.pixels_per_texel > 0.0f ? request.pixels_per_texel
                                                                     : 1.0f;
    const int width = request.images[0].width(), height = request.images[0].height();
    const WorkingScale scale = working_scale(pixels_per_texel, width, height, m_options.patch_size);

    // The exemplar variants are built here, before the images are refined in parallel (each
    // image is independent and draws from its own seed streams, so the order does not matter).
    const std::vector<Variant>* searched = use_surface ? nullptr : &search_variants(scale.exemplar_factor);
    std::vector<const OrientedVariants*> oriented(request.images.size(), nullptr);
    if (use_surface) {
        // Each image's orientation is one serial sum over its pixels (the same bits on any thread
        // count); the images are summed side by side, the variant cache filled after, in order.
        std::vector<Orientation> orientations(request.images.size());
        parallel_for(request.images.size(), 1, [&](std::size_t i0, std::size_t i1) {
            for (std::size_t item = i0; item < i1; ++item) orientations[item] = surface_orientation(request, item);
        });
        for (std::size_t item = 0; item < request.images.size(); ++item)
            oriented[item] = &oriented_variants(orientations[item], scale.exemplar_factor);
    }
    GuidanceResult result;
    result.refined.resize(request.images.size());
    parallel_for(request.images.size(), 1, [&](std::size_t i0, std::size_t i1) {
        for (std::size_t item = i0; item < i1; ++item)
            result.refined[item] = refine_image(request,
                                                item,
                                                use_surface ? oriented[item]->variants : *searched,
                                                use_surface ? oriented[item]->tilts : m_search_tilts,
                                                use_surface,
                                                scale.width,
                                                scale.height);
    });
    return result;
}

Image ExemplarPatchMatchBackend::refine_image(const GuidanceRequest& request, std::size_t item,
                                              const std::vector<Variant>& variants,
                                              const std::vector<std::vector<float>>& tilts, bool use_surface,
                                              int work_width, int work_height) const {
    const Image& input = request.images[item];
    const Image& mask = request.masks[item];
    const int width = input.width(), height = input.height();
    const bool shrink = work_width != width || work_height != height;
    const std::size_t row_grain = 32;
    // The relief on its own: each normal turned by the rotation that stands its surface
    // normal upright, so the surface's curvature does not count as texture.
    Image detail = input;
    if (use_surface) {
        const Image& base = request.surface_normals[item];
        parallel_for(std::size_t(height), row_grain, [&](std::size_t y0, std::size_t y1) {
            for (std::size_t p = y0 * std::size_t(width); p < y1 * std::size_t(width); ++p) {
                if (mask.data()[p] <= 0.0f) continue;
                float* n = detail.data() + 3 * p;
                const float* a = base.data() + 3 * p;
                const Vec3f d = shortest_arc_to_z(Vec3f(a[0], a[1], a[2]), safe_normalize(Vec3f(n[0], n[1], n[2])), false);
                n[0] = d.x, n[1] = d.y, n[2] = d.z;
            }
        });
    }
    // The working copy: the image itself, or its prefiltered coarse copy (only the pixels the
    // copy needs are filtered, no full-size temporaries).
    Image work, work_mask;
    if (shrink) {
        const float ratio = float(work_width) / float(width);
        work = resample_prefiltered(detail, mask, work_width, work_height, ratio);
        work_mask = resample_prefiltered(mask, Image(), work_width, work_height, ratio);
        normalize_vectors(work);
    }
    Image refined =
        synthesize(shrink ? work : detail, shrink ? work_mask : mask, variants, tilts, request.seed, item);

    // Back to full size: with a coarse copy, as a change (the image keeps its own detail finer
    // than the working copy resolves and gains the exemplar's structure at the texel scale),
    // upsampled bilinearly on the fly (the arithmetic of resize_bilinear). Foreground: unit
    // normals (stood back on their surface) times coverage, as the renders are; background:
    // the input.
    if (shrink)
        for (std::size_t i = 0; i < refined.values().size(); ++i) refined.values()[i] -= work.values()[i];
    // Written over `detail` (each pixel reads only its own value first), which is the input on
    // the background already: no second full-size image.
    Image& out = detail;
    const BilinearResizeTaps tx = bilinear_resize_taps(work_width, width), ty = bilinear_resize_taps(work_height, height);
    parallel_for(std::size_t(height), row_grain, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y) {
            const std::size_t ys = std::size_t(y);
            const int iy = ty.i0[ys], iy1 = ty.i1[ys];
            const float wy = ty.w1[ys];
            for (int x = 0; x < width; ++x) {
                const std::size_t p = std::size_t(y) * std::size_t(width) + std::size_t(x);
                const float m = mask.data()[p];
                if (m <= 0.0f) continue;
                float r[3];
                if (shrink) {
                    const int ix = tx.i0[std::size_t(x)], ix1 = tx.i1[std::size_t(x)];
                    const float wx = tx.w1[std::size_t(x)];
                    const float* d = detail.data() + 3 * p;  // read before it is overwritten below
                    for (int ch = 0; ch < 3; ++ch) {
                        const float top = refined.at(ix, iy, ch) * (1 - wx) + refined.at(ix1, iy, ch) * wx;
                        const float bottom =
                            refined.at(ix, iy1, ch) * (1 - wx) + refined.at(ix1, iy1, ch) * wx;
                        r[ch] = d[ch] + (top * (1 - wy) + bottom * wy);
                    }
                } else {
                    std::copy_n(refined.data() + 3 * p, 3, r);
                }
                Vec3f n = safe_normalize(Vec3f(r[0], r[1], r[2]));
                if (use_surface) {
                    const float* a = request.surface_normals[item].data() + 3 * p;
                    n = safe_normalize(shortest_arc_to_z(Vec3f(a[0], a[1], a[2]), n, true));
                }
                float* o = out.data() + 3 * p;
                o[0] = m * n.x, o[1] = m * n.y, o[2] = m * n.z;
            }
        }
    });
    return out;
}

ExemplarPatchMatchBackend::Orientation ExemplarPatchMatchBackend::surface_orientation(const GuidanceRequest& request,
                                                                                     std::size_t item) const {
    // The map's orientation in the image: the coverage-weighted mean of the stood-up tangents
    // (u axis) and the majority handedness.
    const Image& mask = request.masks[item];
    const Image& base = request.surface_normals[item];
    const Image& tangents = request.surface_tangents[item];
    Vec3f mean_tangent;
    double handedness = 0.0;
    for (std::size_t p = 0; p < mask.pixel_count(); ++p) {
        const float m = mask.data()[p];
        if (m <= 0.0f) continue;
        const float* a = base.data() + 3 * p;
        const float* t = tangents.data() + 4 * p;
        mean_tangent += shortest_arc_to_z(Vec3f(a[0], a[1], a[2]), Vec3f(t[0], t[1], t[2]), false) * m;
        handedness += double(m) * double(t[3]);
    }
    const float angle = std::atan2(mean_tangent.y, mean_tangent.x);
    int step = int(std::lround(angle / (2.0f * kPi) * float(kOrientationSteps)));
    step = ((step % kOrientationSteps) + kOrientationSteps) % kOrientationSteps;
    return {step, handedness < 0.0};
}

const ExemplarPatchMatchBackend::OrientedVariants& ExemplarPatchMatchBackend::oriented_variants(Orientation orientation,
                                                                                              float factor) {
    if (factor != m_oriented_factor) {
        m_oriented.clear();
        m_oriented_factor = factor;
    }
    const auto found = m_oriented.find(orientation);
    if (found != m_oriented.end()) return found->second;
    // Quarter turns exactly (they move texels instead of resampling and cropping the exemplar).
    constexpr int kQuarter = kOrientationSteps / 4;
    const float angle = orientation.step % kQuarter == 0
                            ? float(orientation.step / kQuarter) * 0.5f * kPi
                            : 2.0f * kPi * float(orientation.step) / float(kOrientationSteps);
    OrientedVariants oriented;
    for (const Image& scaled : scaled_exemplars(factor))
        oriented.variants.push_back(build_variant(rotate_normal_map(scaled, angle, orientation.mirrored), m_options.levels,
                                                  m_options.patch_size));
    check_variants(oriented.variants, factor);
    oriented.tilts = tilt_tables(oriented.variants);
    return m_oriented.emplace(orientation, std::move(oriented)).first->second;
}

double ExemplarPatchMatchBackend::mean_nearest_patch_distance(const Image& normals, const Image& mask) const {
    TDF_CHECK(!m_search_variants.empty());
    TDF_CHECK_EQ(normals.channels(), 3);
    const int r = m_options.patch_size / 2;
    const int w = normals.width(), h = normals.height();
    // Brute force over every variant position; per-row partial sums reduced in row order.
    std::vector<double> row_sum(std::size_t(h), 0.0);
    std::vector<std::size_t> row_count(std::size_t(h), 0);
    LevelSolver solver(normals, mask, m_search_variants, 0, m_options.patch_size);
    parallel_for(std::size_t(h), 1, [&](std::size_t y0, std::size_t y1) {
        for (int y = int(y0); y < int(y1); ++y) {
            if (y < r || y >= h - r) continue;
            for (int x = r; x < w - r; ++x) {
                if (mask.at(x, y, 0) < 0.5f) continue;
                Match best;
                for (int v = 0; v < int(m_search_variants.size()); ++v) {
                    const Image& e = m_search_variants[std::size_t(v)].levels[0];
                    for (int ey = r; ey < e.height() - r; ++ey)
                        for (int ex = r; ex < e.width() - r; ++ex) {
                            const Match candidate{v, ex, ey, 0.0f};
                            const float d = solver.distance(x, y, candidate, best.d);
                            if (d < best.d) best = candidate, best.d = d;
                        }
                }
                row_sum[std::size_t(y)] += double(best.d) / double((2 * r + 1) * (2 * r + 1));
                ++row_count[std::size_t(y)];
            }
        }
    });
    double sum = 0.0;
    std::size_t count = 0;
    for (int y = 0; y < h; ++y) sum += row_sum[std::size_t(y)], count += row_count[std::size_t(y)];
    return count ? sum / double(count) : 0.0;
}

}  // namespace tdf
