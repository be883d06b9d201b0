#include <tdf/train/texture_fidelity.h>

#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/release.h>
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/gbuffer.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

double psnr_over(const Image& a, const Image& b, const std::vector<std::uint8_t>& covered) {
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t t = 0; t < covered.size(); ++t) {
        if (!covered[t]) continue;
        for (int c = 0; c < 3; ++c) {
            const double e = double(a.data()[3 * t + std::size_t(c)]) - b.data()[3 * t + std::size_t(c)];
            sum += e * e;
        }
        count += 3;
    }
    const double mse = count ? sum / double(count) : 0.0;
    return 10.0 * std::log10(1.0 / std::max(mse, 1e-12));
}

// Mean over covered neighbour pairs of the summed |difference| of the 3 channels, horizontal plus
// vertical (the script's `hf`). `value(t)` is texel t's value (read or derived on the fly, so a
// measure over a 4096^2 map makes no map-sized copy); `include` further restricts which texels
// count.
template <typename Value, typename Include>
double mean_abs_difference(int w, int h, const std::vector<std::uint8_t>& covered, Value value, Include include) {
    double sx = 0, sy = 0;
    std::size_t nx = 0, ny = 0;
    const auto summed = [&](std::size_t a, std::size_t b) {
        const Vec3f va = value(a), vb = value(b);
        double d = 0;
        for (int c = 0; c < 3; ++c) d += std::fabs(double(vb[c]) - va[c]);
        return d;
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t t = std::size_t(y) * std::size_t(w) + std::size_t(x);
            if (!covered[t] || !include(t)) continue;
            if (x + 1 < w && covered[t + 1] && include(t + 1)) sx += summed(t, t + 1), ++nx;
            if (y + 1 < h && covered[t + std::size_t(w)] && include(t + std::size_t(w)))
                sy += summed(t, t + std::size_t(w)), ++ny;
        }
    return (nx ? sx / double(nx) : 0.0) + (ny ? sy / double(ny) : 0.0);
}

// Texel t of a 3-channel map as stored, and as a unit normal (torch F.normalize, eps 1e-12).
Vec3f texel(const Image& map, std::size_t t) {
    const float* v = map.data() + 3 * t;
    return {v[0], v[1], v[2]};
}
Vec3f unit_texel(const Image& map, std::size_t t) { return normalize_or_zero(texel(map, t), 1e-12f); }

}  // namespace

TextureFidelity measure_texture_fidelity(const Image& albedo, const Image& albedo_target, const Image& normal,
                                         const Image& normal_target, const std::vector<std::uint8_t>& covered,
                                         float lowpass_sigma) {
    const int w = albedo.width(), h = albedo.height();
    if (albedo_target.width() != w || albedo_target.height() != h || albedo.channels() != 3 ||
        albedo_target.channels() != 3 || covered.size() != albedo.pixel_count())
        throw_error("texture fidelity: the albedo maps and the coverage differ in size");
    TextureFidelity f;
    std::size_t compared = 0;
    for (std::uint8_t c : covered) compared += c ? 1 : 0;
    f.coverage = double(compared) / double(std::max<std::size_t>(covered.size(), 1));
    f.albedo_psnr = psnr_over(albedo, albedo_target, covered);
    // An empty mask weighs every texel 1 (the bits of a mask of ones, without its copy).
    f.albedo_psnr_lowpass = psnr_over(gaussian_blur_masked(albedo, Image(), lowpass_sigma),
                                      gaussian_blur_masked(albedo_target, Image(), lowpass_sigma), covered);
    const auto all = [](std::size_t) { return true; };
    const auto albedo_at = [&](std::size_t t) { return texel(albedo, t); };
    const auto target_at = [&](std::size_t t) { return texel(albedo_target, t); };
    f.albedo_hf_ratio = mean_abs_difference(w, h, covered, albedo_at, all) /
                        std::max(mean_abs_difference(w, h, covered, target_at, all), 1e-12);
    if (normal.empty() || normal_target.empty()) return f;
    if (normal.width() != w || normal.height() != h || normal_target.width() != w || normal_target.height() != h ||
        normal.channels() != 3 || normal_target.channels() != 3)
        throw_error("texture fidelity: the normal maps differ in size from the albedo maps");
    // The normals are renormalised texel by texel where they are read (no unit copies of the maps).
    const auto n = [&](std::size_t t) { return unit_texel(normal, t); };
    const auto m = [&](std::size_t t) { return unit_texel(normal_target, t); };
    std::vector<double> cosines;
    cosines.reserve(compared);
    for (std::size_t t = 0; t < covered.size(); ++t) {
        if (!covered[t]) continue;
        const Vec3f a = n(t), b = m(t);
        cosines.push_back(double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]);
    }
    double sum = 0;
    for (double c : cosines) sum += c;
    f.normal_mean_cos = cosines.empty() ? 0.0 : sum / double(cosines.size());
    if (!cosines.empty()) {
        const std::size_t rank = std::size_t(0.1 * double(cosines.size() - 1));
        std::nth_element(cosines.begin(), cosines.begin() + std::ptrdiff_t(rank), cosines.end());
        f.normal_p10_cos = cosines[rank];
    }
    release(cosines);
    f.normal_hf_ratio =
        mean_abs_difference(w, h, covered, n, all) / std::max(mean_abs_difference(w, h, covered, m, all), 1e-12);

    // Flat relief: no texel within kFlatRadius (Chebyshev) steeper than 1 degree, so detail that
    // relief-aware shading spreads around a bump (a few texels) does not count as added on flat.
    constexpr int kFlatRadius = 8;
    const float flat_z = std::cos(1.0f * 3.14159265f / 180.0f);
    std::vector<std::uint8_t> steep(covered.size(), 0), steep_rows(covered.size(), 0);
    for (std::size_t t = 0; t < covered.size(); ++t) steep[t] = m(t).z < flat_z ? 1 : 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t any = 0;
            for (int dx = -kFlatRadius; dx <= kFlatRadius && !any; ++dx) {
                const int xx = x + dx;
                if (xx >= 0 && xx < w) any = steep[std::size_t(y) * std::size_t(w) + std::size_t(xx)];
            }
            steep_rows[std::size_t(y) * std::size_t(w) + std::size_t(x)] = any;
        }
    std::vector<std::uint8_t> flat(covered.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::uint8_t any = 0;
            for (int dy = -kFlatRadius; dy <= kFlatRadius && !any; ++dy) {
                const int yy = y + dy;
                if (yy >= 0 && yy < h) any = steep_rows[std::size_t(yy) * std::size_t(w) + std::size_t(x)];
            }
            flat[std::size_t(y) * std::size_t(w) + std::size_t(x)] = any ? 0 : 1;
        }
    std::size_t flat_count = 0;
    for (std::size_t t = 0; t < covered.size(); ++t) flat_count += (flat[t] && covered[t]) ? 1 : 0;
    f.flat_fraction = double(flat_count) / double(std::max<std::size_t>(compared, 1));
    // What the learned albedo adds to the input, texel by texel in float (as an image of the
    // differences would hold it).
    const auto added = [&](std::size_t t) { return texel(albedo, t) - texel(albedo_target, t); };
    const auto is_flat = [&](std::size_t t) { return flat[t] != 0; };
    f.albedo_added_hf_flat = mean_abs_difference(w, h, covered, added, is_flat);
    f.albedo_hf_flat = mean_abs_difference(w, h, covered, target_at, is_flat);
    return f;
}

Json TextureFidelity::to_json() const {
    return {{"albedo_psnr_db", albedo_psnr},         {"albedo_psnr_lowpass_db", albedo_psnr_lowpass},
            {"albedo_hf_ratio", albedo_hf_ratio},    {"albedo_added_hf_where_flat", albedo_added_hf_flat},
            {"albedo_hf_where_flat", albedo_hf_flat}, {"normal_mean_cosine", normal_mean_cos},
            {"normal_p10_cosine", normal_p10_cos},   {"normal_hf_ratio", normal_hf_ratio},
            {"flat_fraction", flat_fraction}, {"coverage", coverage}};
}

namespace {
// The key of an unordered triangle pair.
std::uint64_t pair_key(int a, int b) {
    return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
}
}  // namespace

MeshSeams::MeshSeams(const TriangleMesh& mesh, float crease_degrees) {
    const auto face_normal = [&](int f) {
        const Vec3i& t = mesh.triangles[std::size_t(f)];
        const Vec3f p0 = mesh.positions[std::size_t(t.x)];
        return safe_normalize(cross(mesh.positions[std::size_t(t.y)] - p0, mesh.positions[std::size_t(t.z)] - p0));
    };
    const float crease_cos = std::cos(crease_degrees * 3.14159265f / 180.0f);
    for (const SharedEdge& e : shared_edges(mesh)) {
        EdgeContinuity kind = uv_continuity(mesh, e);
        // A seam along a crease (a mug's base meeting its side) may change colour by design.
        if (kind == EdgeContinuity::Seam && dot(face_normal(e.face[0]), face_normal(e.face[1])) < crease_cos) {
            kind = EdgeContinuity::Apart;
            ++m_crease_edges;
        }
        m_edges[pair_key(e.face[0], e.face[1])] = kind;
        m_seam_edges += kind == EdgeContinuity::Seam ? 1 : 0;
        m_cone_edges += kind == EdgeContinuity::Cone ? 1 : 0;
    }
}

EdgeContinuity MeshSeams::between(int triangle_a, int triangle_b) const {
    if (triangle_a == triangle_b) return EdgeContinuity::Same;
    const auto it = m_edges.find(pair_key(triangle_a, triangle_b));
    return it == m_edges.end() ? EdgeContinuity::Apart : it->second;
}

void SeamJump::add(const GBuffer& g, const Image& image, const MeshSeams& seams) {
    const int c = image.channels();
    // What lies between pixels a and b, or Apart when they are not a surface pair: background, an
    // occlusion edge (a depth jump of more than 1 %, like the handle over the body) or triangles
    // that share no edge.
    const auto continuity = [&](std::size_t a, std::size_t b) {
        if (g.mask[a] <= 0.0f || g.mask[b] <= 0.0f) return EdgeContinuity::Apart;
        if (std::fabs(g.depth[a] - g.depth[b]) > 0.01f * std::max(g.depth[a], g.depth[b])) return EdgeContinuity::Apart;
        return seams.between(g.triangle[a], g.triangle[b]);
    };
    const auto inside = [&](std::size_t a, std::size_t b) {
        const EdgeContinuity k = continuity(a, b);
        return k == EdgeContinuity::Same || k == EdgeContinuity::Continuous;
    };
    const auto jump = [&](std::size_t a, std::size_t b) {
        double diff = 0;
        for (int k = 0; k < c; ++k)
            diff += std::fabs(double(image.data()[b * std::size_t(c) + std::size_t(k)]) -
                              image.data()[a * std::size_t(c) + std::size_t(k)]);
        return diff;
    };
    // The pair (p0 + 2 step, p0 + 3 step) crosses the edge; its baseline is the mean of the two steps
    // before and the two after along the same line, all inside one chart.
    const auto measure = [&](std::size_t p0, std::size_t step) {
        const std::size_t a = p0 + 2 * step, b = a + step;
        const EdgeContinuity kind = continuity(a, b);
        if (kind != EdgeContinuity::Seam && kind != EdgeContinuity::Cone) return;
        double baseline = 0;
        for (int s = 0; s < 5; ++s) {
            if (s == 2) continue;
            const std::size_t u = p0 + std::size_t(s) * step;
            if (!inside(u, u + step)) return;
            baseline += 0.25 * jump(u, u + step);
        }
        if (kind == EdgeContinuity::Seam) {
            seam_sum += jump(a, b);
            interior_sum += baseline;
            ++seam_pairs;
        } else {
            cone_sum += jump(a, b);
            cone_interior_sum += baseline;
            ++cone_pairs;
        }
    };
    for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
            const std::size_t i = g.index(x, y);
            if (x + 5 < g.width) measure(i, 1);
            if (y + 5 < g.height) measure(i, std::size_t(g.width));
        }
}

}  // namespace tdf
