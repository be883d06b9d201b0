// Part segmentation: each source produces named regions per face or per atlas texel; regions
// are matched to parts by the parts' `select`; the other representation is derived (texels
// from faces through the atlas raster, faces from texels by majority).
#include <tdf/parts/part_segmentation.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/colour_segmentation.h>
#include <tdf/parts/external_segmentation.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace tdf {

namespace {

// What a source found: region names and, per face or per texel, a region index (-1 = none).
struct SourceRegions {
    std::vector<std::string> names;
    std::vector<int> face;         // per face, or empty
    std::vector<int> texel;        // per atlas texel, or empty
    std::vector<PartRegion> info;  // extra per-region data (colour), same order as names
    std::vector<double> silhouette;
    int distinct_colours = 0;
};

int region_index(SourceRegions& r, const std::string& name) {
    const auto it = std::find(r.names.begin(), r.names.end(), name);
    if (it != r.names.end()) return int(it - r.names.begin());
    r.names.push_back(name);
    return int(r.names.size()) - 1;
}

std::string hex_colour(Vec3f rgb) {
    const auto byte = [](float v) { return int(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)); };
    return fmt::format("#{:02x}{:02x}{:02x}", byte(rgb.x), byte(rgb.y), byte(rgb.z));
}

std::string list_names(const std::vector<std::string>& names) {
    std::string out;
    for (std::size_t i = 0; i < names.size() && i < 12; ++i) out += (i ? ", " : "") + ("'" + names[i] + "'");
    if (names.size() > 12) out += fmt::format(", ... ({} in all)", names.size());
    return out;
}

SourceRegions mesh_regions(const PartsSpec& spec, const TriangleMesh& mesh, const std::string& where) {
    if (mesh.face_groups.empty())
        throw_error(
            "{}.source: kind 'mesh' but '{}' has no objects, groups or materials (a single region); use "
            "another source",
            where,
            mesh.source_path);
    SourceRegions r;
    const std::string& key = spec.source.key;
    std::vector<int> group_region(mesh.face_groups.size(), -1);
    r.face.resize(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const auto g = std::size_t(mesh.face_group[f]);
        if (group_region[g] < 0) {
            const FaceGroup& fg = mesh.face_groups[g];
            std::string name = key == "material" ? fg.material
                               : key == "object" ? fg.object
                               : key == "group"  ? fg.group
                                                 : std::to_string(g);
            if (name.empty()) name = "(none)";
            group_region[g] = region_index(r, name);
        }
        r.face[f] = group_region[g];
    }
    return r;
}

SourceRegions face_label_regions(const PartsSpec& spec, const TriangleMesh& mesh, const std::string& where) {
    const std::string& path = spec.source.file;
    std::ifstream in(path);
    if (!in) throw_error("{}.source.file: cannot open '{}'", where, path);
    SourceRegions r;
    std::string line;
    std::size_t line_number = 0;
    while (std::getline(in, line)) {
        ++line_number;
        const auto hash = line.find('#');
        if (hash != std::string::npos) line.resize(hash);
        std::istringstream tokens(line);
        std::string label, extra;
        if (!(tokens >> label)) continue;
        if (tokens >> extra)
            throw_error(
                "{}:{}: one label per line expected, got '{}' and '{}'", path, line_number, label, extra);
        if (r.face.size() == mesh.triangles.size())
            throw_error("{}: more labels than the mesh's {} triangles (line {})",
                        path,
                        mesh.triangles.size(),
                        line_number);
        r.face.push_back(region_index(r, label));
    }
    if (r.face.size() != mesh.triangles.size())
        throw_error("{}: {} labels for the mesh's {} triangles (one line per triangle, polygons fanned)",
                    path,
                    r.face.size(),
                    mesh.triangles.size());
    return r;
}

// The source mesh's UV at barycentric b of face f.
Vec2f source_uv(const TriangleMesh& mesh, int f, Vec3f b) {
    const Vec3i& t = mesh.uv_triangles[std::size_t(f)];
    return mesh.uvs[std::size_t(t.x)] * b.x + mesh.uvs[std::size_t(t.y)] * b.y +
           mesh.uvs[std::size_t(t.z)] * b.z;
}

SourceRegions label_image_regions(const PartsSpec& spec, const PartSegmentationInput& in,
                                  const UvRaster& raster, const std::string& where) {
    const TriangleMesh& mesh = *in.mesh;
    if (!mesh.has_uvs())
        throw_error(
            "{}.source: kind 'label_image' needs a mesh with UVs ('{}' has none)", where, mesh.source_path);
    const Image image = read_image(spec.source.image);
    const MipTexture* albedo = in.material ? in.material->albedo : nullptr;
    if (albedo && !albedo->empty() &&
        (image.width() != albedo->width() || image.height() != albedo->height()))
        throw_error(
            "{}.source.image: '{}' is {}x{} but the mesh's albedo texture is {}x{} (paint the labels over "
            "it)",
            where,
            spec.source.image,
            image.width(),
            image.height(),
            albedo->width(),
            albedo->height());
    if (image.channels() < 3)
        throw_error("{}.source.image: '{}' has {} channel(s); an RGB image is needed",
                    where,
                    spec.source.image,
                    image.channels());
    SourceRegions r;
    r.texel.assign(raster.texel_count(), -1);
    std::map<std::uint32_t, int> by_colour;
    const int w = image.width(), h = image.height();
    for (std::size_t i = 0; i < raster.texel_count(); ++i) {
        const int f = raster.triangle[i];
        if (f < 0) continue;
        const Vec2f uv = source_uv(mesh, f, raster.barycentric[i]);
        // Nearest texel, clamped (labels are not interpolated).
        const int x = std::clamp(int(std::floor(uv.x * float(w))), 0, w - 1);
        const int y = std::clamp(int(std::floor((1.f - uv.y) * float(h))), 0, h - 1);
        const float* p = image.pixel(x, y);
        std::uint32_t key = 0;
        for (int c = 0; c < 3; ++c)
            key = key * 256u + std::uint32_t(std::lround(std::clamp(p[c], 0.f, 1.f) * 255.f));
        auto it = by_colour.find(key);
        if (it == by_colour.end()) {
            const Vec3f rgb{
                float(key >> 16) / 255.f, float((key >> 8) & 255u) / 255.f, float(key & 255u) / 255.f};
            it = by_colour.emplace(key, region_index(r, hex_colour(rgb))).first;
            PartRegion info;
            info.has_colour = true;
            info.rgb = rgb;
            r.info.push_back(info);
        }
        r.texel[i] = it->second;
    }
    return r;
}

// Majority filter over the 8 neighbours of each covered texel (itself counted twice), `rounds`
// times, synchronous.
void smooth_texel_labels(std::vector<int>& label, int size, int rounds, int classes) {
    for (int round = 0; round < rounds; ++round) {
        std::vector<int> next(label);
        parallel_for(std::size_t(size), 16, [&](std::size_t begin, std::size_t end) {
            std::vector<int> votes(static_cast<std::size_t>(classes));
            for (std::size_t row = begin; row < end; ++row)
                for (int col = 0; col < size; ++col) {
                    const std::size_t i = row * std::size_t(size) + std::size_t(col);
                    if (label[i] < 0) continue;
                    std::fill(votes.begin(), votes.end(), 0);
                    votes[std::size_t(label[i])] += 2;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int y = int(row) + dy, x = col + dx;
                            if ((dx == 0 && dy == 0) || x < 0 || y < 0 || x >= size || y >= size) continue;
                            const int l = label[std::size_t(y) * std::size_t(size) + std::size_t(x)];
                            if (l >= 0) ++votes[std::size_t(l)];
                        }
                    int best = label[i];
                    for (int l = 0; l < classes; ++l)
                        if (votes[std::size_t(l)] > votes[std::size_t(best)]) best = l;
                    next[i] = best;
                }
        });
        if (next == label) break;
        label.swap(next);
    }
}

SourceRegions colour_regions(const PartsSpec& spec, const PartSegmentationInput& in, const UvRaster& raster,
                             const std::vector<double>& texel_area, const std::string& where) {
    const TriangleMesh& mesh = *in.mesh;
    std::vector<std::size_t> texels;
    for (std::size_t i = 0; i < raster.texel_count(); ++i)
        if (raster.triangle[i] >= 0) texels.push_back(i);
    std::vector<Vec3f> rgb(texels.size());
    parallel_for(texels.size(), 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::size_t i = texels[k];
            rgb[k] = albedo_at(mesh, *in.material, raster.triangle[i], raster.barycentric[i]);
        }
    });
    ColourClusteringOptions options;
    options.k = spec.source.k;
    options.k_max = spec.source.k_max;
    options.seed = in.seed;
    // Weighted by surface area, so clusters are ranked by area even on atlases of uneven density.
    std::vector<float> weight(texels.size());
    double mean = 0;
    for (std::size_t k = 0; k < texels.size(); ++k) mean += texel_area[texels[k]];
    mean = texels.empty() ? 1.0 : mean / double(texels.size());
    for (std::size_t k = 0; k < texels.size(); ++k) weight[k] = float(texel_area[texels[k]] / (mean > 0 ? mean : 1.0));
    const ColourClustering clustering = cluster_colours(rgb, weight, options, where + ".source");
    SourceRegions r;
    r.texel.assign(raster.texel_count(), -1);
    for (std::size_t k = 0; k < texels.size(); ++k) r.texel[texels[k]] = clustering.label[k];
    smooth_texel_labels(r.texel, raster.size, spec.source.smoothing, int(clustering.clusters.size()));
    for (std::size_t c = 0; c < clustering.clusters.size(); ++c) {
        r.names.push_back(std::to_string(c));
        PartRegion info;
        info.has_colour = true;
        info.rgb = clustering.clusters[c].rgb;
        info.lab = clustering.clusters[c].lab;
        r.info.push_back(info);
    }
    r.silhouette = clustering.silhouette;
    r.distinct_colours = clustering.distinct_colours;
    return r;
}

// Each texel's surface area: its face's 3-D area divided by the face's texel count, so atlases
// of uneven density report true areas (region sizes for messages and the report).
std::vector<double> texel_surface_area(const TriangleMesh& mesh, const UvRaster& raster) {
    std::vector<double> texel_area(raster.texel_count(), 0.0);
    std::vector<std::size_t> face_texels(mesh.triangles.size(), 0);
    for (int f : raster.triangle)
        if (f >= 0) ++face_texels[std::size_t(f)];
    for (std::size_t i = 0; i < texel_area.size(); ++i) {
        const int f = raster.triangle[i];
        if (f < 0) continue;
        const Vec3i& t = mesh.triangles[std::size_t(f)];
        const Vec3f p0 = mesh.positions[std::size_t(t.x)];
        const double area = 0.5 * double(length(cross(mesh.positions[std::size_t(t.y)] - p0,
                                                      mesh.positions[std::size_t(t.z)] - p0)));
        texel_area[i] = area / double(face_texels[std::size_t(f)]);
    }
    return texel_area;
}

// The `external` source: the program's faces, regions named by their index.
SourceRegions external_regions(const PartsSpec& spec, const PartSegmentationInput& in, const std::string& where) {
    SourceRegions src;
    ExternalSegmentationInput ext;
    ext.mesh = in.mesh;
    ext.material = in.material;
    ext.work_folder = in.work_folder;
    ext.where = where + ".source.external";
    ext.smoothing = spec.source.smoothing;
    ext.part_names.reserve(spec.parts.size());
    for (const PartSpec& p : spec.parts) ext.part_names.push_back(p.name);
    for (const PartSpec& p : spec.parts) ext.prompts.push_back(p.prompt);
    const std::vector<int> face = run_external_segmentation(spec.source.external, ext);
    src.face = face;
    int top = 0;
    for (int l : face) top = std::max(top, l + 1);
    for (int r = 0; r < top; ++r) src.names.push_back(std::to_string(r));
    return src;
}

// Regions -> parts when parts name their regions ('select'): the named ones, then the rest to the
// part without 'select' (or, for a label image's anti-aliased edge colours, the nearest selected
// colour); `region_fraction` is each region's share of the covered surface.
void select_regions(const PartsSpec& spec, const SourceRegions& src, int catch_all,
                    const std::vector<double>& region_fraction, std::vector<int>& region_part,
                    const std::string& where) {
    const std::string& kind = spec.source.kind;
    const std::size_t parts = spec.parts.size();
    const auto fraction = [&](std::size_t r) { return region_fraction[r]; };
    for (std::size_t p = 0; p < parts; ++p)
        for (const std::string& s : spec.parts[p].select) {
            std::string wanted = s;
            if (kind == "label_image")
                std::transform(wanted.begin(), wanted.end(), wanted.begin(), [](unsigned char c) {
                    return char(std::tolower(c));
                });
            const auto it = std::find(src.names.begin(), src.names.end(), wanted);
            if (it == src.names.end())
                throw_error("{}.list[{}].select: '{}' is not a region of the {} source (found: {})",
                            where,
                            p,
                            s,
                            kind,
                            list_names(src.names));
            region_part[std::size_t(it - src.names.begin())] = int(p);
        }
    for (std::size_t r = 0; r < src.names.size(); ++r) {
        if (region_part[r] >= 0) continue;
        if (catch_all >= 0) {
            region_part[r] = catch_all;
        } else if (kind == "label_image" && fraction(r) < 0.005) {
            // Anti-aliased edge colours of a painted label image: the nearest selected colour.
            float best = 1e30f;
            for (std::size_t q = 0; q < src.names.size(); ++q) {
                if (region_part[q] < 0) continue;
                const float d = length_squared(src.info[q].rgb - src.info[r].rgb);
                if (d < best && fraction(q) >= 0.005) {
                    best = d;
                    region_part[r] = region_part[q];
                }
            }
            if (region_part[r] < 0)
                throw_error("{}: region '{}' is selected by no part", where, src.names[r]);
        } else {
            throw_error(
                "{}: region '{}' ({:.1f} % of the surface) is selected by no part; select it or leave "
                "one "
                "part without 'select' to take the rest",
                where,
                src.names[r],
                100.0 * fraction(r));
        }
    }
}

// Each part's share of the covered surface; a part without faces or texels is an error.
void measure_part_fractions(PartSegmentation& out, const std::vector<double>& texel_area, double covered,
                            const PartsSpec& spec, const std::string& where) {
    const std::size_t parts = spec.parts.size();
    out.part_fraction.assign(parts, 0.0);
    std::vector<std::size_t> part_faces(parts, 0), part_texels(parts, 0);
    for (int l : out.face_part) ++part_faces[std::size_t(l)];
    std::vector<double> part_area(parts, 0.0);
    for (std::size_t i = 0; i < out.texel_part.size(); ++i)
        if (out.texel_part[i] >= 0) {
            ++part_texels[std::size_t(out.texel_part[i])];
            part_area[std::size_t(out.texel_part[i])] += texel_area[i];
        }
    for (std::size_t p = 0; p < parts; ++p) {
        if (part_faces[p] == 0 || part_texels[p] == 0)
            throw_error("{}.list[{}]: part '{}' has no faces{} (check its 'select' with `tdf parts`)",
                        where,
                        p,
                        spec.parts[p].name,
                        part_faces[p] == 0 ? "" : " large enough to cover a texel");
        out.part_fraction[p] = covered > 0 ? part_area[p] / covered : 0.0;
    }
}

}  // namespace

Vec3f albedo_at(const TriangleMesh& mesh, const SurfaceMaterial& material, int face, Vec3f b) {
    using Source = SurfaceMaterial::AlbedoSource;
    switch (material.albedo_source) {
        case Source::Texture: {
            if (!material.albedo || material.albedo->empty() || !mesh.has_uvs()) break;
            float texel[kMaxTextureChannels];
            material.albedo->sample_bilinear(source_uv(mesh, face, b), texel);
            return material.albedo->channels() >= 3 ? Vec3f{texel[0], texel[1], texel[2]}
                                                    : Vec3f{texel[0], texel[0], texel[0]};
        }
        case Source::VertexColors: {
            if (!mesh.has_colors()) break;
            const Vec3i& t = mesh.triangles[std::size_t(face)];
            return mesh.colors[std::size_t(t.x)] * b.x + mesh.colors[std::size_t(t.y)] * b.y +
                   mesh.colors[std::size_t(t.z)] * b.z;
        }
        case Source::Constant:
            break;
    }
    return material.albedo_constant;
}

std::vector<int> texel_labels_from_faces(const UvRaster& raster, const std::vector<int>& face_label) {
    std::vector<int> out(raster.texel_count(), -1);
    for (std::size_t i = 0; i < out.size(); ++i)
        if (raster.triangle[i] >= 0) out[i] = face_label[std::size_t(raster.triangle[i])];
    return out;
}

std::vector<std::vector<std::pair<int, float>>> face_adjacency(const TriangleMesh& mesh) {
    struct Edge {
        std::uint64_t key;
        int face;
    };
    std::vector<Edge> edges;
    edges.reserve(mesh.triangles.size() * 3);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
        for (int k = 0; k < 3; ++k) {
            const auto a = std::uint32_t(mesh.triangles[f][k]),
                       b = std::uint32_t(mesh.triangles[f][(k + 1) % 3]);
            edges.push_back({(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), int(f)});
        }
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
        return x.key != y.key ? x.key < y.key : x.face < y.face;
    });
    std::vector<std::vector<std::pair<int, float>>> out(mesh.triangles.size());
    for (std::size_t s = 0; s < edges.size();) {
        std::size_t e = s;
        while (e < edges.size() && edges[e].key == edges[s].key) ++e;
        const Vec3f pa = mesh.positions[std::size_t(edges[s].key >> 32)];
        const Vec3f pb = mesh.positions[std::size_t(edges[s].key & 0xffffffffu)];
        const float len = std::max(length(pa - pb), 1e-12f);
        for (std::size_t i = s; i < e; ++i)
            for (std::size_t j = s; j < e; ++j)
                if (i != j && edges[i].face != edges[j].face)
                    out[std::size_t(edges[i].face)].push_back({edges[j].face, len});
        s = e;
    }
    return out;
}

std::vector<int> face_labels_from_texels(const TriangleMesh& mesh, const UvRaster& raster,
                                         const std::vector<int>& texel_label, int fallback) {
    int classes = 0;
    for (int l : texel_label) classes = std::max(classes, l + 1);
    const std::size_t faces = mesh.triangles.size();
    std::vector<std::vector<int>> votes(faces);
    for (std::size_t i = 0; i < raster.texel_count(); ++i) {
        const int f = raster.triangle[i];
        if (f < 0 || texel_label[i] < 0) continue;
        auto& v = votes[std::size_t(f)];
        if (v.empty()) v.assign(std::size_t(classes), 0);
        ++v[std::size_t(texel_label[i])];
    }
    std::vector<int> out(faces, -1);
    for (std::size_t f = 0; f < faces; ++f)
        if (!votes[f].empty())
            out[f] = int(std::max_element(votes[f].begin(), votes[f].end()) - votes[f].begin());
    // Faces without texels (smaller than a texel): propagate from labelled neighbours.
    if (std::find(out.begin(), out.end(), -1) != out.end()) {
        const auto adjacency = face_adjacency(mesh);
        for (bool changed = true; changed;) {
            changed = false;
            std::vector<int> next(out);
            for (std::size_t f = 0; f < faces; ++f) {
                if (out[f] >= 0) continue;
                std::vector<float> v(std::size_t(std::max(classes, 1)), 0.f);
                bool any = false;
                for (const auto& [g, w] : adjacency[f])
                    if (out[std::size_t(g)] >= 0) {
                        v[std::size_t(out[std::size_t(g)])] += w;
                        any = true;
                    }
                if (any) {
                    next[f] = int(std::max_element(v.begin(), v.end()) - v.begin());
                    changed = true;
                }
            }
            out.swap(next);
        }
        for (int& l : out)
            if (l < 0) l = fallback;
    }
    return out;
}

Json PartSegmentation::report(const PartsSpec& spec) const {
    Json parts = Json::array();
    for (std::size_t p = 0; p < part_names.size(); ++p) {
        std::size_t faces = 0, texels = 0;
        for (int l : face_part) faces += l == int(p);
        for (int l : texel_part) texels += l == int(p);
        Json regions_of = Json::array();
        for (const PartRegion& r : regions)
            if (r.part == int(p)) regions_of.push_back(r.name);
        parts.push_back({{"index", p},
                         {"name", part_names[p]},
                         {"faces", faces},
                         {"texels", texels},
                         {"fraction", part_fraction[p]},
                         {"regions", regions_of}});
    }
    Json found = Json::array();
    for (const PartRegion& r : regions) {
        Json j = {{"name", r.name},
                  {"part", r.part >= 0 ? Json(part_names[std::size_t(r.part)]) : Json(nullptr)},
                  {"fraction", r.fraction}};
        if (r.has_colour) {
            j["rgb"] = {int(std::lround(r.rgb.x * 255.f)),
                        int(std::lround(r.rgb.y * 255.f)),
                        int(std::lround(r.rgb.z * 255.f))};
            j["hex"] = hex_colour(r.rgb);
            if (spec.source.kind == "colour") j["lab"] = {r.lab.x, r.lab.y, r.lab.z};
        }
        found.push_back(j);
    }
    Json out = {{"source", spec.source.kind},
                {"size", size},
                {"parts", parts},
                {"regions", found},
                {"seconds", seconds}};
    if (spec.source.kind == "mesh") out["key"] = spec.source.key;
    if (spec.source.kind == "colour") {
        out["distinct_colours"] = distinct_colours;
        out["k"] = regions.size();
        if (!silhouette.empty()) {
            Json s = Json::object();
            for (std::size_t i = 0; i < silhouette.size(); ++i) s[std::to_string(i + 2)] = silhouette[i];
            out["silhouette_by_k"] = s;
        }
    }
    return out;
}

PartSegmentation segment_parts(const PartsSpec& spec, const PartSegmentationInput& in) {
    const auto start = std::chrono::steady_clock::now();
    const std::string where = in.where.empty() ? std::string("parts") : in.where;
    if (!in.mesh || !in.atlas || !in.material)
        throw_error("{}: segment_parts needs a mesh, an atlas and a material", where);
    if (spec.parts.empty()) throw_error("{}: at least 1 part is needed", where);
    if (in.atlas->triangles.size() != in.mesh->triangles.size())
        throw_error("{}: the atlas has {} faces but the mesh {}",
                    where,
                    in.atlas->triangles.size(),
                    in.mesh->triangles.size());
    if (in.size < 16 || in.size > 16384)
        throw_error("{}: texel raster size {} is not in [16, 16384]", where, in.size);
    UvRaster raster = rasterize_uv(*in.atlas, in.size);
    add_partial_texels(*in.atlas, raster);

    const std::vector<double> texel_area = texel_surface_area(*in.mesh, raster);
    SourceRegions src;
    const std::string& kind = spec.source.kind;
    if (spec.parts.size() == 1) {
        // One part is the whole surface: there is nothing to tell apart, so the source is not read.
        src.names = {"surface"};
        src.face.assign(in.mesh->triangles.size(), 0);
    } else if (kind == "mesh") {
        src = mesh_regions(spec, *in.mesh, where);
    } else if (kind == "face_labels") {
        src = face_label_regions(spec, *in.mesh, where);
    } else if (kind == "label_image") {
        src = label_image_regions(spec, in, raster, where);
    } else if (kind == "colour") {
        src = colour_regions(spec, in, raster, texel_area, where);
    } else if (kind == "external") {
        src = external_regions(spec, in, where);
    } else {
        throw_error("{}.source: unknown kind '{}'", where, kind);
    }
    if (src.info.size() < src.names.size()) src.info.resize(src.names.size());

    // Regions -> parts.
    const std::size_t parts = spec.parts.size();
    std::vector<int> region_part(src.names.size(), -1);
    int catch_all = -1;
    bool any_select = false;
    for (std::size_t p = 0; p < parts; ++p) {
        if (spec.parts[p].select.empty())
            catch_all = int(p);
        else
            any_select = true;
    }
    std::vector<double> region_area(src.names.size(), 0.0);
    double covered = 0;
    {
        const std::vector<int> texel_region =
            src.texel.empty() ? texel_labels_from_faces(raster, src.face) : src.texel;
        for (std::size_t i = 0; i < texel_region.size(); ++i)
            if (texel_region[i] >= 0) {
                region_area[std::size_t(texel_region[i])] += texel_area[i];
                covered += texel_area[i];
            }
    }
    const auto fraction = [&](std::size_t r) { return covered > 0 ? region_area[r] / covered : 0.0; };
    if (!any_select) {
        if (src.names.size() != parts)
            throw_error(
                "{}: the {} source found {} regions ({}) but there are {} parts; give the parts a 'select' "
                "(run `tdf parts` to see the regions)",
                where,
                kind,
                src.names.size(),
                list_names(src.names),
                parts);
        for (std::size_t r = 0; r < parts; ++r) region_part[r] = int(r);
    } else {
        std::vector<double> region_fraction(src.names.size());
        for (std::size_t r = 0; r < region_fraction.size(); ++r) region_fraction[r] = fraction(r);
        select_regions(spec, src, catch_all, region_fraction, region_part, where);
    }

    PartSegmentation out;
    for (const PartSpec& p : spec.parts) out.part_names.push_back(p.name);
    out.size = in.size;
    const auto map_label = [&](std::vector<int> labels) {
        for (int& l : labels)
            if (l >= 0) l = region_part[std::size_t(l)];
        return labels;
    };
    if (!src.texel.empty()) {
        out.texel_part = map_label(src.texel);
        out.face_part =
            face_labels_from_texels(*in.mesh, raster, out.texel_part, catch_all >= 0 ? catch_all : 0);
        if (kind == "colour" && spec.source.smoothing > 0)
            log_verbose("{}: colour regions smoothed over {} rounds", where, spec.source.smoothing);
    } else {
        out.face_part = map_label(src.face);
        for (int& l : out.face_part)
            if (l < 0) l = catch_all >= 0 ? catch_all : 0;
        out.texel_part = texel_labels_from_faces(raster, out.face_part);
    }
    measure_part_fractions(out, texel_area, covered, spec, where);
    for (std::size_t r = 0; r < src.names.size(); ++r) {
        PartRegion info = src.info[r];
        info.name = src.names[r];
        info.part = region_part[r];
        info.fraction = fraction(r);
        out.regions.push_back(info);
    }
    out.silhouette = src.silhouette;
    out.distinct_colours = src.distinct_colours;
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

}  // namespace tdf
