#pragma once
/// Renders the passes of one view of a textured mesh (what `tdf render` draws): traces each
/// tile into a GBuffer and shades it right away (spec 3.1-3.5 for training shading, 3.9 for
/// the visualizer's). SSAA renders at the internal size and resizes every pass back (3.8).
///
/// Not reproduced: nvdiffrast's analytic silhouette antialiasing (spec 3.6). Without SSAA the
/// coverage is hard (1 sample per pixel); compare silhouettes with an eroded mask.
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/frame.h>
#include <tdf/render/shading.h>
#include <tdf/render/texture.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>

#include <vector>

namespace tdf {

/// What the surface looks like. Textures are borrowed and must outlive the renderer.
struct SurfaceMaterial {
    enum class AlbedoSource { Texture, VertexColors, Constant };
    AlbedoSource albedo_source = AlbedoSource::Constant;
    const MipTexture* albedo = nullptr;  ///< RGB(A) in [0,1] (1-channel: grey); for Texture
    Vec3f albedo_constant{0.5f, 0.5f, 0.5f};
    /// Tangent-space normal map decoded to [-1, 1] (x/255*2-1, spec 1.3); nullptr = flat (0,0,1).
    const MipTexture* tactile = nullptr;
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

struct RenderSettings {
    ShadingMode shading = ShadingMode::Training;
    /// How albedo and shade combine in the lambertian pass (shading.h lit_color); the albedo
    /// pass shows the stored values in both (what a viewer displays for an unlit texel).
    ColorSpace color_space = ColorSpace::Raw;
    Vec3f background{1, 1, 1};  ///< composited behind albedo and lambertian (spec 3.6: white)
};

class Renderer {
public:
    /// `scene` must have been built from `mesh`; both are borrowed.
    Renderer(const TriangleMesh& mesh, const EmbreeScene& scene, const SurfaceMaterial& material,
             const RenderSettings& settings = {});

    /// Renders `passes` at camera.width x camera.height, one sample per pixel.
    Frame render(const Camera& camera, const Light& light, const std::vector<Pass>& passes) const;
    /// The same into `frame`, reusing its images when passes and size match (no allocation).
    void render(const Camera& camera, const Light& light, const std::vector<Pass>& passes, Frame& frame) const;
    /// Renders at the SSAA internal size (ceil(size * ssaa / 8) * 8 per side when ssaa != 1,
    /// spec 2.3) and resizes every pass back to camera.width x camera.height (spec 3.8).
    Frame render_ssaa(const Camera& camera, float ssaa, const Light& light, const std::vector<Pass>& passes) const;

private:
    const TriangleMesh& m_mesh;
    const EmbreeScene& m_scene;
    SurfaceMaterial m_material;
    RenderSettings m_settings;
};

}  // namespace tdf
