// Composition of the per-part tactile targets over the atlas, and the label map exports.
#include <tdf/parts/part_target.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/render/material_sampling.h>
#include <tdf/tactile/tactile_map.h>

#include <algorithm>
#include <cmath>

namespace tdf {

namespace {

constexpr double kPi = 3.14159265358979323846;

void check_raster(const std::vector<int>& labels, int size, const char* what) {
    if (size <= 0 || labels.size() != std::size_t(size) * std::size_t(size))
        throw_error("{}: {} labels for a {}x{} raster", what, labels.size(), size, size);
}

Vec3f texel3(const Image& image, std::size_t i) {
    const float* p = image.data() + i * 3;
    return {p[0], p[1], p[2]};
}

double angle_degrees(Vec3f a, Vec3f b) {
    const double c = std::clamp(double(dot(safe_normalize(a), safe_normalize(b))), -1.0, 1.0);
    return std::acos(c) * 180.0 / kPi;
}

// Per texel: centre distance to the nearest texel of another part within `radius`, and that
// part; (inf, -1) when none.
void nearest_other(const std::vector<int>& labels, int size, int radius, std::vector<float>& distance,
                   std::vector<int>& other) {
    distance.assign(labels.size(), 1e30f);
    other.assign(labels.size(), -1);
    parallel_for(std::size_t(size), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t row = begin; row < end; ++row)
            for (int col = 0; col < size; ++col) {
                const std::size_t i = row * std::size_t(size) + std::size_t(col);
                const int own = labels[i];
                if (own < 0) continue;
                for (int dy = -radius; dy <= radius; ++dy)
                    for (int dx = -radius; dx <= radius; ++dx) {
                        const int y = int(row) + dy, x = col + dx;
                        if (x < 0 || y < 0 || x >= size || y >= size) continue;
                        const int l = labels[std::size_t(y) * std::size_t(size) + std::size_t(x)];
                        if (l < 0 || l == own) continue;
                        const float d = std::sqrt(float(dx * dx + dy * dy));
                        if (d < distance[i] || (d == distance[i] && l < other[i])) {
                            distance[i] = d;
                            other[i] = l;
                        }
                    }
            }
    });
}

}  // namespace

Vec3f blend_normals(Vec3f a, Vec3f b, float w) {
    // Slopes (x/z, y/z) of the two surfaces; blending heights blends slopes linearly. Dividing
    // by sqrt(w^2 + (1-w)^2) keeps the detail's amplitude: two independent textures averaged
    // linearly lose up to 1 - 1/sqrt(2) of it at w = 0.5, a flattened line along the boundary.
    const float za = std::max(a.z, 1e-3f), zb = std::max(b.z, 1e-3f);
    const float norm = 1.f / std::sqrt(w * w + (1.f - w) * (1.f - w));
    const float sx = (w * a.x / za + (1.f - w) * b.x / zb) * norm;
    const float sy = (w * a.y / za + (1.f - w) * b.y / zb) * norm;
    return safe_normalize(Vec3f{sx, sy, 1.f});
}

std::vector<Image> lay_part_maps(const std::vector<PartTactile>& parts, int size) {
    if (size < 1) throw_error("lay_part_maps: size {} < 1", size);
    std::vector<Image> layers;
    for (std::size_t p = 0; p < parts.size(); ++p) {
        const PartTactile& part = parts[p];
        if (!part.map || part.map->empty()) throw_error("lay_part_maps: part {} has no tactile map", p);
        if (part.map->channels() < 3)
            throw_error("lay_part_maps: part {}'s tactile map has {} channels", p, part.map->channels());
        if (!(part.uv_scale > 0) || !std::isfinite(part.uv_scale))
            throw_error("lay_part_maps: part {} has uv scale {}", p, part.uv_scale);
        Image layer(size, size, 3);
        parallel_for(std::size_t(size), 16, [&](std::size_t begin, std::size_t end) {
            float texel[kMaxTextureChannels];
            for (std::size_t row = begin; row < end; ++row)
                for (int col = 0; col < size; ++col) {
                    const Vec2f uv{(float(col) + 0.5f) / float(size),
                                   1.f - (float(row) + 0.5f) / float(size)};
                    part.map->sample_bilinear(uv * part.uv_scale, texel);
                    const Vec3f n = safe_normalize(Vec3f{texel[0], texel[1], texel[2]});
                    float* out = layer.pixel(col, int(row));
                    out[0] = n.x;
                    out[1] = n.y;
                    out[2] = n.z;
                }
        });
        layers.push_back(std::move(layer));
    }
    return layers;
}

Image compose_part_target(const std::vector<int>& labels, int size, const std::vector<Image>& layers,
                          float band, int gutter) {
    check_raster(labels, size, "compose_part_target");
    if (!(band >= 0.f && band <= 4.f)) throw_error("compose_part_target: band {} is not in [0, 4]", band);
    for (std::size_t p = 0; p < layers.size(); ++p)
        if (layers[p].width() != size || layers[p].height() != size || layers[p].channels() != 3)
            throw_error("compose_part_target: layer {} is {}x{}x{}, expected {}x{}x3",
                        p,
                        layers[p].width(),
                        layers[p].height(),
                        layers[p].channels(),
                        size,
                        size);
    for (int l : labels)
        if (l >= int(layers.size()))
            throw_error("compose_part_target: label {} but only {} layers", l, layers.size());
    std::vector<float> distance;
    std::vector<int> other;
    nearest_other(labels, size, int(std::ceil(band)) + 1, distance, other);
    Image out(size, size, 3);
    parallel_for(labels.size(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            Vec3f n{0, 0, 1};
            const int own = labels[i];
            if (own >= 0) {
                n = texel3(layers[std::size_t(own)], i);
                if (other[i] >= 0 && band > 0.f) {
                    const float w = std::min(1.f, 0.5f + 0.5f * (distance[i] - 0.5f) / band);
                    if (w < 1.f) n = blend_normals(n, texel3(layers[std::size_t(other[i])], i), w);
                }
            }
            out.data()[i * 3] = n.x;
            out.data()[i * 3 + 1] = n.y;
            out.data()[i * 3 + 2] = n.z;
        }
    });
    if (gutter > 0) {
        const std::vector<int> grown = dilate_labels(labels, size, gutter);
        for (std::size_t i = 0; i < labels.size(); ++i)
            if (labels[i] < 0 && grown[i] >= 0) {
                const Vec3f n = texel3(layers[std::size_t(grown[i])], i);
                std::copy(&n.x, &n.x + 3, out.data() + i * 3);
            }
    }
    return out;
}

std::vector<int> downsample_labels(const std::vector<int>& labels, int size) {
    check_raster(labels, size, "downsample_labels");
    const int half = std::max(1, size / 2);
    std::vector<int> out(std::size_t(half) * std::size_t(half), -1);
    for (int y = 0; y < half; ++y)
        for (int x = 0; x < half; ++x) {
            int cand[4], n = 0;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const int sx = std::min(2 * x + dx, size - 1), sy = std::min(2 * y + dy, size - 1);
                    const int l = labels[std::size_t(sy) * std::size_t(size) + std::size_t(sx)];
                    if (l >= 0) cand[n++] = l;
                }
            int best = -1, best_count = 0;
            for (int a = 0; a < n; ++a) {
                int c = 0;
                for (int b = 0; b < n; ++b) c += cand[b] == cand[a];
                if (c > best_count || (c == best_count && cand[a] < best)) {
                    best = cand[a];
                    best_count = c;
                }
            }
            out[std::size_t(y) * std::size_t(half) + std::size_t(x)] = best;
        }
    return out;
}

std::vector<int> dilate_labels(const std::vector<int>& labels, int size, int texels) {
    check_raster(labels, size, "dilate_labels");
    std::vector<int> current = labels;
    for (int ring = 0; ring < texels; ++ring) {
        std::vector<int> next = current;
        bool grew = false;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(size) + std::size_t(x);
                if (current[i] >= 0) continue;
                int best = -1;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int sx = x + dx, sy = y + dy;
                        if (sx < 0 || sy < 0 || sx >= size || sy >= size) continue;
                        const int l = current[std::size_t(sy) * std::size_t(size) + std::size_t(sx)];
                        if (l >= 0 && (best < 0 || l < best)) best = l;
                    }
                if (best >= 0) {
                    next[i] = best;
                    grew = true;
                }
            }
        current.swap(next);
        if (!grew) break;
    }
    return current;
}

Image part_mask(const std::vector<int>& labels, int size, int part) {
    check_raster(labels, size, "part_mask");
    Image mask(size, size, 1);
    for (std::size_t i = 0; i < labels.size(); ++i) mask.data()[i] = labels[i] == part ? 1.f : 0.f;
    return mask;
}

PartBoundaryMeasure measure_part_boundary(const Image& composed, const std::vector<int>& labels, int size,
                                          const std::vector<Image>& layers, float band,
                                          double tolerance_degrees) {
    check_raster(labels, size, "measure_part_boundary");
    std::vector<float> distance;
    std::vector<int> other;
    nearest_other(labels, size, 6, distance, other);
    const auto slope = [](Vec3f n) {
        return std::sqrt(double(n.x) * n.x + double(n.y) * n.y) / std::max(double(n.z), 1e-3);
    };
    PartBoundaryMeasure m;
    m.part_bleed_texels.assign(layers.size(), 0.0);
    double boundary_sum = 0, material_sum = 0, interior_sum = 0, detail_sum = 0, detail_reference = 0;
    std::size_t interior_pairs = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const std::size_t i = std::size_t(y) * std::size_t(size) + std::size_t(x);
            const int own = labels[i];
            if (own < 0) continue;
            const Vec3f n = texel3(composed, i);
            if (angle_degrees(n, texel3(layers[std::size_t(own)], i)) > tolerance_degrees) {
                double& bleed = m.part_bleed_texels[std::size_t(own)];
                bleed = std::max(bleed, double(other[i] >= 0 ? distance[i] : 1e9f));
                m.bleed_texels = std::max(m.bleed_texels, bleed);
            }
            if (other[i] >= 0 && distance[i] <= band + 0.5f) {
                detail_sum += slope(n);
                detail_reference += 0.5 * (slope(texel3(layers[std::size_t(own)], i)) +
                                           slope(texel3(layers[std::size_t(other[i])], i)));
                ++m.band_texels;
            }
            for (int k = 0; k < 2; ++k) {
                if ((k == 0 && x + 1 >= size) || (k == 1 && y + 1 >= size)) continue;
                const std::size_t j = k == 0 ? i + 1 : i + std::size_t(size);
                if (labels[j] < 0) continue;
                const double a = angle_degrees(n, texel3(composed, j));
                if (labels[j] != own) {
                    boundary_sum += a;
                    // What a hard cut shows at this pair: one material's texel against the other's.
                    material_sum += angle_degrees(texel3(layers[std::size_t(own)], i),
                                                  texel3(layers[std::size_t(labels[j])], j));
                    ++m.boundary_pairs;
                } else if (other[i] < 0 && other[j] < 0) {  // no other part within 6 texels
                    interior_sum += a;
                    ++interior_pairs;
                }
            }
        }
    if (m.boundary_pairs) {
        m.boundary_step_degrees = boundary_sum / double(m.boundary_pairs);
        m.hard_step_degrees = material_sum / double(m.boundary_pairs);
    }
    m.interior_step_degrees = interior_pairs ? interior_sum / double(interior_pairs) : 0.0;
    m.step_ratio = m.hard_step_degrees > 0 ? m.boundary_step_degrees / m.hard_step_degrees : 0.0;
    m.band_detail_ratio = detail_reference > 0 ? detail_sum / detail_reference : 1.0;
    return m;
}

Vec3f part_colour(int index) {
    static const Vec3f kFixed[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}};
    if (index >= 0 && index < 6) return kFixed[index];
    // Golden-angle hues at full saturation, value 0.8.
    const double h = std::fmod(double(index) * 137.50776405, 360.0) / 60.0;
    const double x = 1.0 - std::fabs(std::fmod(h, 2.0) - 1.0);
    const double v = 0.8;
    Vec3f rgb;
    switch (int(h)) {
        case 0:
            rgb = {1, float(x), 0};
            break;
        case 1:
            rgb = {float(x), 1, 0};
            break;
        case 2:
            rgb = {0, 1, float(x)};
            break;
        case 3:
            rgb = {0, float(x), 1};
            break;
        case 4:
            rgb = {float(x), 0, 1};
            break;
        default:
            rgb = {1, 0, float(x)};
            break;
    }
    return rgb * float(v);
}

Json write_part_maps(const std::string& base, const std::vector<int>& labels, int size,
                     const std::vector<std::string>& names, int gutter) {
    check_raster(labels, size, "write_part_maps");
    const std::vector<int> dilated = dilate_labels(labels, size, gutter);
    Image map(size, size, 3, 0.f);
    for (std::size_t i = 0; i < dilated.size(); ++i)
        if (dilated[i] >= 0) {
            const Vec3f c = part_colour(dilated[i]);
            for (int k = 0; k < 3; ++k) map.data()[i * 3 + std::size_t(k)] = c[k];
        }
    write_atomically(base + "_label_map.png", [&](const std::string& tmp) { write_png(tmp, map); });
    std::size_t covered = 0;
    for (int l : labels) covered += l >= 0;
    Json legend = Json::array();
    for (std::size_t p = 0; p < names.size(); ++p) {
        std::size_t texels = 0;
        for (int l : labels) texels += l == int(p);
        const Vec3f c = part_colour(int(p));
        legend.push_back(
            {{"index", p},
             {"name", names[p]},
             {"colour",
              {int(std::lround(c.x * 255)), int(std::lround(c.y * 255)), int(std::lround(c.z * 255))}},
             {"texels", texels},
             {"fraction", covered ? double(texels) / double(covered) : 0.0},
             {"mask", base.substr(base.find_last_of('/') + 1) + "_mask_" + names[p] + ".png"}});
        const Image mask = part_mask(dilated, size, int(p));
        write_atomically(base + "_mask_" + names[p] + ".png",
                         [&](const std::string& tmp) { write_png(tmp, mask); });
    }
    write_text_atomically(base + "_label_legend.json",
                          Json{{"size", size}, {"parts", legend}}.dump(2) + "\n");
    return legend;
}

ScenePartMaps lay_scene_part_maps(const PartsSpec& spec, const TriangleMesh& atlas, int size,
                                  const std::string& where) {
    std::vector<MipTexture> maps;
    std::vector<PartTactile> tactile;
    maps.reserve(spec.parts.size());  // PartTactile points into it: no reallocation
    for (const PartSpec& p : spec.parts) {
        const TactileMap map = load_tactile_map(p.tactile_images.front());
        maps.emplace_back(map.normals);
        float scale = p.layout.repeat;
        if (p.layout.mode == "physical") {
            const float mm_per_pixel = p.layout.mm_per_pixel > 0 ? p.layout.mm_per_pixel : map.mm_per_pixel;
            if (!(mm_per_pixel > 0))
                throw_error("{}: part '{}': layout.mode is 'physical' but '{}' has no tdf:mm_per_pixel metadata and "
                            "layout.mm_per_pixel is not set",
                            where, p.name, p.tactile_images.front());
            scale = physical_tactile_uv_scale(atlas, p.layout.mm_per_unit, map.normals.width(), mm_per_pixel);
        }
        tactile.push_back({&maps.back(), scale});
    }
    ScenePartMaps out;
    for (const PartTactile& t : tactile) out.uv_scales.push_back(t.uv_scale);
    out.layers = lay_part_maps(tactile, size);
    return out;
}

}  // namespace tdf
