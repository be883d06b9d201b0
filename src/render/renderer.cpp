#include <tdf/core/error.h>
#include <tdf/core/image_ops.h>
#include <tdf/core/parallel.h>
#include <tdf/render/material_sampling.h>
#include <tdf/render/raster.h>
#include <tdf/render/renderer.h>
#include <tdf/render/shade_lanes.h>
#include <tdf/render/shading.h>
#include <tdf/render/stream_lanes.h>
#include <tdf/render/trace.h>
#include <tdf/scene/view_sampler.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>

namespace tdf {

const char* shading_mode_name(ShadingMode mode) {
    return mode == ShadingMode::Training ? "training" : "visualizer";
}

ShadingMode parse_shading_mode(const std::string& name) {
    if (name == "training") return ShadingMode::Training;
    if (name == "visualizer") return ShadingMode::Visualizer;
    throw_error("unknown shading mode '{}' (valid: training, visualizer)", name);
}

const char* visibility_name(Visibility visibility) {
    return visibility == Visibility::Ray ? "ray" : "raster";
}

Visibility parse_visibility(const std::string& name) {
    if (name == "ray") return Visibility::Ray;
    if (name == "raster") return Visibility::Raster;
    throw_error("unknown renderer '{}' (valid: ray, raster)", name);
}

Renderer::Renderer(const TriangleMesh& mesh, const EmbreeScene& scene, const SurfaceMaterial& material,
                   const RenderSettings& settings)
    : m_mesh(mesh), m_scene(scene), m_material(material), m_settings(settings) {
    using Source = SurfaceMaterial::AlbedoSource;
    if (material.albedo_source == Source::Texture && (!material.albedo || material.albedo->empty()))
        throw_error("{}: the albedo source is a texture but no texture was given", mesh.source_path);
    if (material.albedo_source == Source::VertexColors && !mesh.has_colors())
        throw_error("{}: the albedo source is vertex colours but the mesh has none", mesh.source_path);
    const bool textured = material.albedo_source == Source::Texture || material.tactile || material.label;
    if (textured && !mesh.has_uvs())
        throw_error("{}: textures need UVs but the mesh has none", mesh.source_path);
    if (material.tactile && material.tactile->channels() < 3)
        throw_error("{}: the tactile normal map needs 3 channels, it has {}",
                    mesh.source_path,
                    material.tactile->channels());
    if (settings.antialias) m_topology = EdgeTopology(mesh.triangles, mesh.positions.size());
}

namespace {

// The frame's images by pass, nullptr for passes not requested: the choice of passes is made
// once a tile, without lookups or allocation.
struct Targets {
    std::array<float*, kPassCount> base{};
    float* coverage = nullptr;
};

inline void put3(float* out, Vec3f v) {
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}

// The mip LOD of one pixel depends only on the texture's size: textures of equal size (an
// albedo and a tactile map, typically) share one computation.
class PixelLod {
public:
    PixelLod(Vec2f duv_dx, Vec2f duv_dy) : m_dx(duv_dx), m_dy(duv_dy) {}
    float of(const MipTexture& tex) {
        if (tex.width() != m_width || tex.height() != m_height) {
            m_width = tex.width();
            m_height = tex.height();
            m_lod = tex.level_of_detail(m_dx, m_dy);
        }
        return m_lod;
    }

private:
    Vec2f m_dx, m_dy;
    int m_width = -1, m_height = -1;
    float m_lod = 0;
};

// Samples a texture into a 3-vector: RGB, or grey for 1-2 channels.
Vec3f sample_rgb(const MipTexture& tex, Vec2f uv, PixelLod& lod, bool mipmapped, int max_level) {
    float texel[kMaxTextureChannels];
    if (mipmapped)
        tex.sample_trilinear_at(uv, lod.of(tex), texel, max_level);
    else
        tex.sample_bilinear(uv, texel);
    return texel_rgb(tex, texel);
}

// Stage 2 of the renderer: turns G-buffer tiles into passes. Knows nothing about which
// producer filled the tile.
class TileShader {
public:
    TileShader(const TriangleMesh& mesh, const SurfaceMaterial& material, const RenderSettings& settings,
               const Camera& camera, const Light& light, const Targets& targets)
        : m_mesh(mesh),
          m_mat(material),
          m_background(settings.background),
          m_color_space(settings.color_space),
          m_training(settings.shading == ShadingMode::Training),
          m_tactile_max_level(m_training ? -1 : 5),  // spec 3.9: max_mip_level = 5
          m_albedo_mipmapped(m_training),            // visualizer: plain bilinear
          m_need_frame(targets.base[std::size_t(Pass::Lambertian)] ||
                       targets.base[std::size_t(Pass::ShadingNormal)] ||
                       targets.base[std::size_t(Pass::ShadingNormalViewspace)] ||
                       targets.base[std::size_t(Pass::TactileNormal)]),
          m_need_albedo(targets.base[std::size_t(Pass::Albedo)] ||
                        targets.base[std::size_t(Pass::Lambertian)]),
          m_tactile_scale(material.tactile_layout.uv_scale),
          m_tactile_lod_offset(std::log2(m_tactile_scale)),
          m_targets(targets),
          m_image_width(camera.width),
          m_paired_maps(m_training && material.albedo_source == SurfaceMaterial::AlbedoSource::Texture &&
                        material.tactile && m_tactile_scale == 1.f &&
                        material.albedo->width() == material.tactile->width() &&
                        material.albedo->height() == material.tactile->height()) {
        m_lane_constants.training = m_training;
        m_lane_constants.view = {camera.right, camera.up, camera.back};
        m_lane_constants.point_light = light.kind == Light::Kind::Point;
        m_lane_constants.light_vector = light.vector;
        m_lane_constants.ambient = light.ambient;
    }

    // Shades G-buffer tile `g`, whose pixel (0, 0) is image pixel (x0, y0), into the frame: the
    // texture lookups for the whole tile, the shading arithmetic over the whole tile at once
    // (shade_lanes), then the passes.
    void shade(const GBufferLanes& g, int x0, int y0) const {
        static thread_local ShadeLanes lanes;  // per thread, reused: no allocation per tile
        fill_lanes(g, lanes);
        if (m_need_frame) shade_lanes(g, lanes, m_lane_constants);
        write_passes(g, lanes, x0, y0);
        streaming_fence();
    }

private:
    // The passes one at a time over the whole tile, from the lanes straight into the frame's
    // images (stream_lanes.h); the passes that are not a plane of the lanes as they are (the
    // flipped v, the label and lit colours) are made in lanes first. Background pixels get the
    // G-buffer's zeros, and the background colour where it is composited.
    void write_passes(const GBufferLanes& g, const ShadeLanes& l, int x0, int y0) const {
        static thread_local TilePixelLanes layout;
        static thread_local struct {
            alignas(64) float v_flipped[ShadeLanes::kMax];
            alignas(64) float colour[3][ShadeLanes::kMax];
        } extra;
        layout.build(g);
        const int n = g.count;
        const float* mask = g.mask;
        const auto pass = [&](Pass p) { return m_targets.base[std::size_t(p)]; };
        const auto put = [&](float* image, std::initializer_list<const float*> planes, const float* hits) {
            stream_lanes(layout, planes.begin(), int(planes.size()), hits, image, m_image_width, x0, y0);
        };
        // A pass of one colour a lane, made in lanes first.
        const auto put_colours = [&](float* image, auto&& colour_of_lane) {
            for (int i = 0; i < n; ++i) {
                const Vec3f c = colour_of_lane(i);
                extra.colour[0][i] = c.x, extra.colour[1][i] = c.y, extra.colour[2][i] = c.z;
            }
            put(image, {extra.colour[0], extra.colour[1], extra.colour[2]}, nullptr);
        };
        put(m_targets.coverage, {mask}, nullptr);
        if (float* o = pass(Pass::Mask)) put(o, {mask}, nullptr);
        if (float* o = pass(Pass::Depth)) put(o, {g.depth}, nullptr);
        if (float* o = pass(Pass::Normal)) put(o, {g.nx, g.ny, g.nz}, nullptr);
        if (float* o = pass(Pass::Tangent)) put(o, {g.tx, g.ty, g.tz}, nullptr);
        if (float* o = pass(Pass::Uv)) {
            for (int i = 0; i < n; ++i) extra.v_flipped[i] = 1.f - g.v[i];  // the reference's v' (spec 3.9)
            put(o, {g.u, extra.v_flipped}, mask);
        }
        if (float* o = pass(Pass::Label))
            put_colours(o, [&](int i) {
                return g.pixel[i] >= 0 && mask[i] > 0.f && m_mat.label
                           ? sample_lane(*m_mat.label, g, i, true, m_tactile_max_level)
                           : Vec3f{};
            });
        if (float* o = pass(Pass::Albedo))  // misses hold the background (fill_lanes)
            put(o, {l.albedo[0], l.albedo[1], l.albedo[2]}, nullptr);
        if (!m_need_frame) return;
        // Lanes that missed hold what shading made of zeros: masked to zeros.
        if (float* o = pass(Pass::TactileNormal)) put(o, {l.tnx, l.tny, l.tnz}, mask);
        if (float* o = pass(Pass::ShadingNormal)) put(o, {l.snx, l.sny, l.snz}, mask);
        if (float* o = pass(Pass::ShadingNormalViewspace)) put(o, {l.vx, l.vy, l.vz}, mask);
        if (float* o = pass(Pass::Lambertian))
            put_colours(o, [&](int i) {
                return mask[i] > 0.f ? lit_color(l.albedo_at(i), l.shade[i], m_color_space) : m_background;
            });
    }

    static UvLanes uv_lanes(const GBufferLanes& g) { return {g.u, g.v, g.du_dx, g.dv_dx, g.du_dy, g.dv_dy}; }

    // One lookup of `tex` at lane i of `g` (sample_rgb), for the maps not looked up a tile at once.
    static Vec3f sample_lane(const MipTexture& tex, const GBufferLanes& g, int i, bool mipmapped,
                             int max_level) {
        const UvLanes uv = uv_lanes(g);
        const std::size_t k = std::size_t(i);
        PixelLod lod(uv.duv_dx(k), uv.duv_dy(k));
        return sample_rgb(tex, uv.uv(k), lod, mipmapped, max_level);
    }

    // The albedo of hit lane i, when the maps are not looked up as a pair.
    Vec3f albedo_at(const GBufferLanes& g, int i) const {
        using Source = SurfaceMaterial::AlbedoSource;
        if (m_mat.albedo_source == Source::Texture)
            return sample_lane(*m_mat.albedo, g, i, m_albedo_mipmapped, -1);
        if (m_mat.albedo_source == Source::VertexColors)
            return vertex_color_at(m_mesh, g.triangle[i], {g.b1[i], g.b2[i]});
        return m_mat.albedo_constant;
    }

    // Planes for lookups of maps with other than 3 channels (sample_trilinear_pairs and
    // sample_trilinear_many write one plane a channel).
    struct TilePlanes {
        float lod[ShadeLanes::kMax];
        float albedo[kMaxTextureChannels][ShadeLanes::kMax];
        float tactile[kMaxTextureChannels][ShadeLanes::kMax];
    };

    // The lanes' inputs: the texture lookups of the hits, RGB maps straight into the lanes'
    // planes. The tactile map is looked up for the whole tile at once, together with the albedo
    // when both maps have one size and one filter (training shading's default: one LOD and one
    // bilinear footprint a level for both).
    void fill_lanes(const GBufferLanes& g, ShadeLanes& l) const {
        const std::size_t n = std::size_t(g.count);
        l.count = g.count;
        const bool want_tactile = m_need_frame && m_mat.tactile;
        const bool pairs = m_paired_maps && m_need_albedo && want_tactile;
        static thread_local TilePlanes tile;
        const std::size_t plane = ShadeLanes::kMax;
        const int ca = m_mat.albedo ? m_mat.albedo->channels() : 0;
        const int ct = m_mat.tactile ? m_mat.tactile->channels() : 0;
        float* albedo = ca == 3 ? l.albedo[0] : tile.albedo[0];
        float* tactile = ct == 3 ? l.p[0] : tile.tactile[0];
        const UvLanes uv = uv_lanes(g);
        if (pairs)
            m_mat.albedo->sample_trilinear_pairs(
                *m_mat.tactile, n, g.mask, uv, tile.lod, albedo, tactile, plane, -1);
        else if (want_tactile)
            // The layout scales UVs and therefore their derivatives: LOD + log2(scale).
            m_mat.tactile->sample_trilinear_many(n,
                                                 g.mask,
                                                 uv,
                                                 m_tactile_scale,
                                                 m_tactile_lod_offset,
                                                 tile.lod,
                                                 tactile,
                                                 plane,
                                                 m_tactile_max_level);
        const auto set = [](float(*planes)[ShadeLanes::kMax], std::size_t i, Vec3f v) {
            planes[0][i] = v.x, planes[1][i] = v.y, planes[2][i] = v.z;
        };
        for (std::size_t i = 0; i < n; ++i) {
            if (!(g.mask[i] > 0.f)) {
                set(l.albedo, i, m_background);
                set(l.p, i, {0, 0, 1});
                continue;
            }
            // Maps of 1, 2 or 4+ channels were looked up into the tile's planes.
            if (pairs) {
                if (ca != 3) set(l.albedo, i, texel_rgb(*m_mat.albedo, &tile.albedo[0][i], plane));
            } else {
                set(l.albedo, i, m_need_albedo ? albedo_at(g, int(i)) : m_background);
            }
            if (!want_tactile)
                set(l.p, i, {0, 0, 1});
            else if (ct != 3)
                set(l.p, i, texel_rgb(*m_mat.tactile, &tile.tactile[0][i], plane));
        }
    }

    const TriangleMesh& m_mesh;
    const SurfaceMaterial& m_mat;
    Vec3f m_background;
    ColorSpace m_color_space;
    bool m_training;
    int m_tactile_max_level;
    bool m_albedo_mipmapped;
    bool m_need_frame;
    bool m_need_albedo;
    float m_tactile_scale;
    float m_tactile_lod_offset;
    Targets m_targets;
    int m_image_width;
    bool m_paired_maps;
    ShadeConstants m_lane_constants;
};

}  // namespace

Frame Renderer::render(const Camera& camera, const Light& light, const std::vector<Pass>& passes) const {
    Frame frame;
    render(camera, light, passes, frame);
    return frame;
}

void Renderer::render(const Camera& camera, const Light& light, const std::vector<Pass>& passes,
                      Frame& frame) const {
    if (camera.width <= 0 || camera.height <= 0)
        throw_error(
            "image size {}x{} is empty (width and height must be positive)", camera.width, camera.height);
    // Reuse the frame's images when the layout matches: every pixel is overwritten below.
    const bool reuse = frame.passes == passes && frame.coverage.width() == camera.width &&
                       frame.coverage.height() == camera.height;
    if (!reuse) {
        frame.passes = passes;
        frame.images.clear();
        frame.coverage = Image(camera.width, camera.height, 1);
    }
    Targets targets;
    for (std::size_t k = 0; k < passes.size(); ++k) {
        const Pass p = passes[k];
        if (targets.base[std::size_t(p)]) throw_error("pass '{}' is requested twice", pass_name(p));
        if (!reuse) frame.images.emplace_back(camera.width, camera.height, pass_channels(p));
        targets.base[std::size_t(p)] = frame.images[k].data();
    }
    targets.coverage = frame.coverage.data();
    const TileShader shader(m_mesh, m_material, m_settings, camera, light, targets);

    // Stage 1 (visibility): the producer that fills each G-buffer tile. The rasterizer draws the
    // whole image once (it bins triangles to tiles itself); the tracer traces tile by tile.
    const bool raster = m_settings.visibility == Visibility::Raster;
    const bool antialias = m_settings.antialias;
    // Per call, not thread_local: a caller may render several views in parallel, and the worker
    // threads below must all read this call's buffer.
    RasterBuffer raster_buffer;
    std::vector<Vec4f> clip;
    if (raster || antialias) clip = clip_positions(m_mesh, camera);
    if (raster) rasterize(clip, m_mesh.triangles, camera.width, camera.height, raster_buffer);
    auto produce_tile = [&](int x0, int y0, int x1, int y1, GBufferLanes& lanes) {
        if (raster) {
            static thread_local GBuffer g;  // per thread, reused across tiles and frames
            interpolate_tile(raster_buffer, m_mesh, camera, x0, y0, x1, y1, g);
            lanes.assign(g);
        } else {
            trace_tile_lanes(m_scene, m_mesh, camera, x0, y0, x1, y1, lanes);
        }
    };
    // What antialiasing needs from visibility: triangle ids and a depth ordered like z/w.
    const std::size_t pixel_count = std::size_t(camera.width) * std::size_t(camera.height);
    std::vector<int> aa_triangle(antialias ? pixel_count : 0);
    std::vector<float> aa_depth(antialias ? pixel_count : 0);

    // Stage 2 (shading): one path for both producers.
    parallel_for_tiles(
        camera.width, camera.height, kTraceTileWidth, kTraceTileHeight, [&](int x0, int y0, int x1, int y1) {
            // One G-buffer tile per thread, reused across tiles and frames: stays in cache.
            static thread_local GBufferLanes g;
            produce_tile(x0, y0, x1, y1, g);
            shader.shade(g, x0, y0);
            if (antialias)
                for (int i = 0; i < g.count; ++i) {
                    if (g.pixel[i] < 0) continue;
                    const int x = x0 + g.pixel[i] % g.width, y = y0 + g.pixel[i] / g.width;
                    const std::size_t px = std::size_t(y) * std::size_t(camera.width) + std::size_t(x);
                    aa_triangle[px] = g.triangle[i];
                    aa_depth[px] = raster ? raster_buffer.rast[px].z : g.depth[i];
                }
        });
    if (!raster) m_scene.throw_if_error("rendering");

    // Stage 3 (antialiasing): shared by both producers.
    if (antialias) {
        AntialiasPlan plan;
        plan.analyze(camera.width,
                     camera.height,
                     aa_triangle.data(),
                     aa_depth.data(),
                     clip,
                     m_mesh.triangles,
                     m_topology);
        antialias_frame(plan, frame);
    }
}

void Renderer::antialias_frame(const AntialiasPlan& plan, Frame& frame) const {
    const Vec3f bg = m_settings.background;
    const float* hard = frame.coverage.data();
    auto image_of = [&](Pass p) -> Image* {
        for (std::size_t k = 0; k < frame.passes.size(); ++k)
            if (frame.passes[k] == p) return &frame.images[k];
        return nullptr;
    };
    if (m_settings.shading == ShadingMode::Training) {
        // Spec 3.6: AA(x), then out = alpha AA(x) + (1 - alpha) background with the hard alpha.
        for (Pass p : {Pass::Lambertian,
                       Pass::Albedo,
                       Pass::TactileNormal,
                       Pass::ShadingNormal,
                       Pass::ShadingNormalViewspace,
                       Pass::Label}) {
            Image* image = image_of(p);
            if (!image) continue;
            plan.apply(*image);
            if (p != Pass::Lambertian && p != Pass::Albedo && p != Pass::TactileNormal) continue;
            const Vec3f back = p == Pass::TactileNormal ? Vec3f{} : bg;
            for (std::size_t i = 0; i < image->pixel_count(); ++i)
                if (!(hard[i] > 0.f)) put3(image->data() + 3 * i, back);
        }
        return;
    }
    // Spec 3.9: alpha = clamp(AA(hard coverage), 0, 1); c alpha + background (1 - alpha), c = 0
    // off the mesh. The mask pass itself stays hard.
    Image alpha = frame.coverage;
    plan.apply(alpha);
    for (Pass p : {Pass::Lambertian, Pass::Albedo}) {
        Image* image = image_of(p);
        if (!image) continue;
        for (std::size_t i = 0; i < image->pixel_count(); ++i) {
            const float a = std::clamp(alpha.data()[i], 0.f, 1.f);
            float* o = image->data() + 3 * i;
            const bool covered = hard[i] > 0.f;
            for (int k = 0; k < 3; ++k) o[k] = (covered ? o[k] : 0.f) * a + bg[k] * (1.f - a);
        }
    }
}

Frame Renderer::render_ssaa(const Camera& camera, float ssaa, const Light& light,
                            const std::vector<Pass>& passes) const {
    if (!(ssaa >= 1.f) || ssaa > 8.f) throw_error("SSAA factor {} is outside [1, 8]", ssaa);
    if (ssaa == 1.f) return render(camera, light, passes);
    Camera internal = camera;
    internal.width = ssaa_internal_resolution(camera.width, ssaa);
    internal.height = ssaa_internal_resolution(camera.height, ssaa);
    Frame frame = render(internal, light, passes);
    for (Image& image : frame.images) image = resize_bilinear(image, camera.width, camera.height);
    frame.coverage = resize_bilinear(frame.coverage, camera.width, camera.height);
    return frame;
}

}  // namespace tdf
