#include <tdf/render/renderer.h>

#include <tdf/render/material_sampling.h>

#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/resample.h>
#include <tdf/render/shading.h>
#include <tdf/render/trace.h>
#include <tdf/scene/view_sampler.h>

#include <algorithm>
#include <array>

namespace tdf {

const char* shading_mode_name(ShadingMode mode) {
    return mode == ShadingMode::Training ? "training" : "visualizer";
}

ShadingMode parse_shading_mode(const std::string& name) {
    if (name == "training") return ShadingMode::Training;
    if (name == "visualizer") return ShadingMode::Visualizer;
    throw_error("unknown shading mode '{}' (valid: training, visualizer)", name);
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
        throw_error("{}: the tactile normal map needs 3 channels, it has {}", mesh.source_path,
                    material.tactile->channels());
}

namespace {

// Per-pass output pointers, nullptr for passes not requested: the pixel loop writes straight
// into the images without lookups or allocation.
struct Targets {
    std::array<float*, kPassCount> base{};
    std::array<int, kPassCount> channels{};
    float* coverage = nullptr;
    float* at(Pass p, std::size_t pixel) const {
        float* b = base[std::size_t(p)];
        return b ? b + pixel * std::size_t(channels[std::size_t(p)]) : nullptr;
    }
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

}  // namespace

Frame Renderer::render(const Camera& camera, const Light& light, const std::vector<Pass>& passes) const {
    Frame frame;
    render(camera, light, passes, frame);
    return frame;
}

void Renderer::render(const Camera& camera, const Light& light, const std::vector<Pass>& passes, Frame& frame) const {
    if (camera.width <= 0 || camera.height <= 0)
        throw_error("image size {}x{} is empty (width and height must be positive)", camera.width, camera.height);
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
        targets.channels[std::size_t(p)] = pass_channels(p);
    }
    targets.coverage = frame.coverage.data();

    const bool training = m_settings.shading == ShadingMode::Training;
    const int tactile_max_level = training ? -1 : 5;  // spec 3.9: max_mip_level = 5
    const bool albedo_mipmapped = training;           // visualizer: plain bilinear
    using Source = SurfaceMaterial::AlbedoSource;
    const SurfaceMaterial& mat = m_material;
    const bool need_frame = targets.base[std::size_t(Pass::Lambertian)] ||
                            targets.base[std::size_t(Pass::ShadingNormal)] ||
                            targets.base[std::size_t(Pass::ShadingNormalViewspace)] ||
                            targets.base[std::size_t(Pass::TactileNormal)];
    const bool need_albedo = targets.base[std::size_t(Pass::Albedo)] || targets.base[std::size_t(Pass::Lambertian)];

    parallel_for_tiles(camera.width, camera.height, kTraceTile, [&](int x0, int y0, int x1, int y1) {
        // One small G-buffer per thread, reused across tiles and frames: stays in cache.
        static thread_local GBuffer g;
        trace_tile(m_scene, m_mesh, camera, x0, y0, x1, y1, g);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const std::size_t i = g.index(x - x0, y - y0);
                const std::size_t px = std::size_t(y) * std::size_t(camera.width) + std::size_t(x);
                const bool hit = g.mask[i] > 0.f;
                PixelLod lod(g.duv_dx[i], g.duv_dy[i]);
                targets.coverage[px] = g.mask[i];
                if (float* o = targets.at(Pass::Mask, px)) o[0] = g.mask[i];
                if (float* o = targets.at(Pass::Depth, px)) o[0] = g.depth[i];
                if (float* o = targets.at(Pass::Normal, px)) put3(o, g.normal[i]);
                if (float* o = targets.at(Pass::Tangent, px)) put3(o, g.tangent[i]);
                if (float* o = targets.at(Pass::Uv, px)) {
                    o[0] = hit ? g.uv[i].x : 0.f;
                    o[1] = hit ? 1.f - g.uv[i].y : 0.f;  // the reference's v' (spec 3.9)
                }
                if (float* o = targets.at(Pass::Label, px))
                    put3(o, hit && mat.label ? sample_rgb(*mat.label, g.uv[i], lod, true, tactile_max_level)
                                             : Vec3f{});
                Vec3f albedo = m_settings.background;
                if (need_albedo && hit) {
                    if (mat.albedo_source == Source::Texture)
                        albedo = sample_rgb(*mat.albedo, g.uv[i], lod, albedo_mipmapped, -1);
                    else if (mat.albedo_source == Source::VertexColors)
                        albedo = vertex_color_at(m_mesh, g, i);
                    else
                        albedo = mat.albedo_constant;
                }
                if (float* o = targets.at(Pass::Albedo, px)) put3(o, albedo);
                if (!need_frame) continue;
                if (!hit) {
                    for (Pass p : {Pass::TactileNormal, Pass::ShadingNormal, Pass::ShadingNormalViewspace})
                        if (float* o = targets.at(p, px)) put3(o, {});
                    if (float* o = targets.at(Pass::Lambertian, px)) put3(o, m_settings.background);
                    continue;
                }
                Vec3f p{0, 0, 1};
                if (mat.tactile) {
                    float texel[kMaxTextureChannels];
                    mat.tactile->sample_trilinear_at(g.uv[i], lod.of(*mat.tactile), texel, tactile_max_level);
                    p = {texel[0], texel[1], texel[2]};
                    if (training) p = safe_normalize(p);  // spec 3.1 step 5
                }
                if (float* o = targets.at(Pass::TactileNormal, px)) put3(o, p);
                const Vec3f raw = shading_normal_unnormalized(g.tangent[i], g.normal[i], g.handedness[i], p);
                const Vec3f n = safe_normalize(raw);
                if (float* o = targets.at(Pass::ShadingNormal, px)) put3(o, n);
                if (float* o = targets.at(Pass::ShadingNormalViewspace, px))
                    put3(o, training ? normalize_or_zero(camera.world_to_camera_direction(n))
                                     : camera.world_to_camera_direction(raw));
                if (float* o = targets.at(Pass::Lambertian, px)) {
                    const Vec3f l = light.kind == Light::Kind::Point ? safe_normalize(light.vector - g.position[i])
                                                                    : light.vector;
                    const float shade = light.ambient + (1.f - light.ambient) * std::max(0.f, dot(n, l));
                    put3(o, lit_color(albedo, shade, m_settings.color_space));
                }
            }
    });
    m_scene.throw_if_error("rendering");
}

Frame Renderer::render_ssaa(const Camera& camera, float ssaa, const Light& light,
                            const std::vector<Pass>& passes) const {
    if (!(ssaa >= 1.f) || ssaa > 8.f) throw_error("SSAA factor {} is outside [1, 8]", ssaa);
    if (ssaa == 1.f) return render(camera, light, passes);
    Camera internal = camera;
    internal.width = ssaa_internal_resolution(camera.width, ssaa);
    internal.height = ssaa_internal_resolution(camera.height, ssaa);
    Frame frame = render(internal, light, passes);
    for (Image& image : frame.images) image = downsample_bilinear(image, camera.width, camera.height);
    frame.coverage = downsample_bilinear(frame.coverage, camera.width, camera.height);
    return frame;
}

}  // namespace tdf
