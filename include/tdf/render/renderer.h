#pragma once
/// Renders the passes of one view of a textured mesh (what `tdf render` draws) in three stages:
///   1. visibility: a producer fills G-buffer tiles (gbuffer.h): Embree rays (trace.h) or the
///      nvdiffrast-rules rasterizer (raster.h: rasterize once, interpolate per tile);
///   2. shading: one code path turns every G-buffer tile into the passes, whichever producer
///      made it (spec 3.1-3.5 for training shading, 3.9 for the visualizer's);
///   3. antialiasing (optional, either producer): dr.antialias (antialias.h) on the passes the
///      reference antialiases (spec 3.6 training, 3.9 visualizer), then SSAA resizing (3.8).
/// Tiles are shaded right after they are produced, from a small cache-resident buffer.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/antialias.h>
#include <tdf/render/frame.h>
#include <tdf/render/shading.h>
#include <tdf/render/texture.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>

#include <vector>

namespace tdf {

/// What the surface looks like. Textures are borrowed and must outlive the renderer.
/// How a tactile map is laid on the surface: uv' = uv * uv_scale. 1 covers the UV atlas once (the
/// reference, spec 1.3.5); a larger value repeats a tileable map at its physical size
/// (physical_tactile_uv_scale). The renderer and the optimizer read it from the same material.
struct TactileLayoutTransform {
    float uv_scale = 1.0f;
};

struct SurfaceMaterial {
    enum class AlbedoSource { Texture, VertexColors, Constant };
    AlbedoSource albedo_source = AlbedoSource::Constant;
    const MipTexture* albedo = nullptr;  ///< RGB(A) in [0,1] (1-channel: grey); for Texture
    Vec3f albedo_constant{0.5f, 0.5f, 0.5f};
    /// Tangent-space normal map decoded to [-1, 1] (x/255*2-1, spec 1.3); nullptr = flat (0,0,1).
    const MipTexture* tactile = nullptr;
    TactileLayoutTransform tactile_layout;  ///< how `tactile` repeats over the atlas
    /// Label map (RGB in [0,1]) for the label pass; nullptr = zeros.
    const MipTexture* label = nullptr;
};

/// A light for the lambertian pass: shade = ambient + (1 - ambient) max(0, n . l). The
/// training renderer's 0.5 max(0, n.l) + 0.5 is ambient 0.5 (spec 3.4); the visualizer uses 0.1.
struct Light {
    enum class Kind { Point, Directional };
    Kind kind = Kind::Directional;
    Vec3f vector{0, 0, 1};  ///< Point: world position. Directional: unit direction TOWARD the light.
    float ambient = 0.5f;
};

enum class ShadingMode {
    /// The training renderer (spec 3.1-3.5): albedo and tactile map trilinear over the whole
    /// pyramid, tactile normal renormalised per pixel, view-space normal normalised.
    Training,
    /// vis_render.py (spec 3.9): albedo bilinear without mips, tactile and label maps trilinear
    /// capped at mip level 5 and not renormalised, view-space normal NOT normalised (13.19).
    Visualizer,
};
const char* shading_mode_name(ShadingMode mode);
/// "training" or "visualizer"; throws tdf::Error otherwise.
ShadingMode parse_shading_mode(const std::string& name);

/// Which producer computes visibility (stage 1).
enum class Visibility {
    Ray,     ///< Embree primary rays; UV derivatives from ray differentials
    Raster,  ///< the rasterizer with nvdiffrast's rules; UV derivatives as dr.interpolate
};
const char* visibility_name(Visibility visibility);
/// "ray" or "raster"; throws tdf::Error otherwise.
Visibility parse_visibility(const std::string& name);

struct RenderSettings {
    ShadingMode shading = ShadingMode::Training;
    /// How albedo and shade combine in the lambertian pass (shading.h lit_color); the albedo
    /// pass shows the stored values in both (what a viewer displays for an unlit texel).
    ColorSpace color_space = ColorSpace::Raw;
    Vec3f background{1, 1, 1};  ///< composited behind albedo and lambertian (spec 3.6: white)
    Visibility visibility = Visibility::Ray;
    /// dr.antialias on the shaded passes, as the reference applies it: training shading
    /// antialiases lambertian, albedo, tactile_normal, shading_normal, shading_normal_viewspace
    /// and label, then re-composites albedo, lambertian and tactile_normal with the hard coverage
    /// (spec 3.6); visualizer shading antialiases only the coverage and blends albedo and
    /// lambertian over the background with it, c alpha + background (1 - alpha) with c = 0 off
    /// the mesh (spec 3.9). mask, depth, normal, tangent and uv stay hard in both.
    bool antialias = false;
};

class Renderer {
public:
    /// `scene` must have been built from `mesh`; both are borrowed (the raster producer does not
    /// trace, but the scene keeps one constructor for both).
    Renderer(const TriangleMesh& mesh, const EmbreeScene& scene, const SurfaceMaterial& material,
             const RenderSettings& settings = {});

    /// Renders `passes` at camera.width x camera.height, one sample per pixel.
    Frame render(const Camera& camera, const Light& light, const std::vector<Pass>& passes) const;
    /// The same into `frame`, reusing its images when passes and size match (no allocation).
    void render(const Camera& camera, const Light& light, const std::vector<Pass>& passes,
                Frame& frame) const;
    /// Renders at the SSAA internal size (ceil(size * ssaa / 8) * 8 per side when ssaa != 1,
    /// spec 2.3) and resizes every pass back to camera.width x camera.height (spec 3.8).
    Frame render_ssaa(const Camera& camera, float ssaa, const Light& light,
                      const std::vector<Pass>& passes) const;

    const RenderSettings& settings() const { return m_settings; }

private:
    // Stage 3: dr.antialias on the passes the shading mode antialiases (see RenderSettings).
    void antialias_frame(const AntialiasPlan& plan, Frame& frame) const;

    const TriangleMesh& m_mesh;
    const EmbreeScene& m_scene;
    SurfaceMaterial m_material;
    RenderSettings m_settings;
    EdgeTopology m_topology;  ///< built when antialias is on
};

}  // namespace tdf
