#pragma once
/// Scene files: JSON describing a mesh, its materials, views, light and output passes, read by
/// `tdf render` and shared with the optimizer (docs/scene-format.md lists every key).
///
/// - Unknown keys are errors. The top-level sections "optimize", "tactile_layout", "guidance"
///   and "export" belong to other modules: they are kept as raw JSON in `sections` for their
///   owners to validate; any other unknown top-level key is rejected here.
/// - `"parent": "base.json"` inherits keys from another file (objects merge, values replace).
/// - `key=value` overrides (dotted paths, e.g. `image.width=256`) apply after inheritance.
/// - Relative paths resolve against the folder of the scene file named on the command line
///   (also for inherited keys and overrides); they may point outside the repository, e.g. into
///   ../shared/data.
#include <tdf/core/config.h>
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace tdf {

/// Limits checked when a scene is parsed, so that a typo cannot ask for terabytes:
/// views of all kinds together, and the side of a supersampled render (image side x ssaa).
inline constexpr int kMaxSceneViews = 10000;
inline constexpr int kMaxRenderSide = 16384;

/// One fixed orbit camera (spec 2.1); radius and fovy default to views.radius / views.fovy.
struct OrbitViewSpec {
    float elevation = 0;
    float azimuth = 0;
    float radius = 3;
    float fovy = 50;
};

struct ViewsSpec {
    float radius = 3.f;              ///< default orbit radius (vis_render.py: 3)
    float fovy = 50.f;               ///< default vertical field of view, degrees (vis_render.py: 50)
    Vec3f target{};                  ///< orbit centre
    std::vector<OrbitViewSpec> orbit;  ///< explicit views, rendered first
    int turntable_count = 0;         ///< N views at azimuth 360 k / N
    float turntable_elevation = 0;
    int random_count = 0;            ///< visual training views (spec 2.3), from `seed`
    bool random_ssaa = false;        ///< give random views the reference's random SSAA factor
    int patch_count = 0;             ///< tactile patch views (spec 2.4), from `seed`
    bool patch_reference_flip = false;  ///< store patches upside down like the reference (13.13)
};

struct LightSpec {
    /// "camera": directional, from the view's angles plus the relative offsets (vis_render.py
    /// stills; patch views use the camera direction); "directional": fixed angles; "point":
    /// fixed position; "magic3d": the training renderer's random point light (spec 3.4), one per
    /// view from `seed`.
    std::string mode = "camera";
    float relative_elevation = 0;
    float relative_azimuth = 0;
    float elevation = 0;
    float azimuth = 0;
    Vec3f position{0, 0, 3};
    float ambient = 0.1f;  ///< default by shading mode: training 0.5 (spec 3.4), visualizer 0.1 (3.9)
};

/// How one part's tactile map is laid on the atlas (docs/multi-part-textures.md).
struct PartLayoutSpec {
    std::string mode = "atlas";  ///< "atlas": covers the atlas `repeat` times; "physical": real size
    float repeat = 1.f;          ///< atlas mode: uv' = uv * repeat, > 0
    float mm_per_unit = 0.f;     ///< physical mode: millimetres per mesh unit (required there)
    float mm_per_pixel = 0.f;    ///< physical mode: overrides the map's tdf:mm_per_pixel when > 0
};

/// One part of a multi-part scene: its own tactile map(s), layout and guidance settings.
struct PartSpec {
    std::string name;                         ///< [A-Za-z0-9_-]+, unique; names the mask files
    std::vector<std::string> tactile_images;  ///< resolved paths (at least one)
    PartLayoutSpec layout;
    std::string prompt;              ///< guidance prompt ("" = the trainer's default)
    Json guidance = Json::object();  ///< raw per-part guidance settings (the trainer's)
    /// Which regions of the source belong to this part: material/object/group names (mesh),
    /// "#rrggbb" colours (label_image), labels (face_labels), cluster indices (colour), mask
    /// indices (external). Empty: see PartsSpec.
    std::vector<std::string> select;
};

/// Where the parts come from (`parts.source`).
struct PartsSourceSpec {
    /// mesh | label_image | face_labels | colour | external
    std::string kind = "mesh";
    std::string key = "material";    ///< mesh: material | object | group | primitive
    std::string image;               ///< label_image: resolved path of an image in the mesh's UV space
    std::string file;                ///< face_labels: resolved path of the per-face label file
    int k = 0;                       ///< colour: clusters; 0 = choose in [2, k_max]
    int k_max = 6;                   ///< colour: largest K tried when k = 0, [2, 16]
    int smoothing = 3;               ///< colour / external: rounds of neighbourhood majority, [0, 50]
    Json external = Json::object();  ///< external: the program settings (docs/parts-protocol.md)
};

/// `parts`: N >= 2 parts and their source. Regions are matched to parts by each part's
/// `select`; one part may leave `select` empty and takes every region no other part selects;
/// when no part has a `select`, region i (in the source's order) goes to part i and the source
/// must find exactly N regions.
struct PartsSpec {
    PartsSourceSpec source;
    std::vector<PartSpec> parts;
    bool enabled() const { return !parts.empty(); }
};

struct SceneDescription {
    std::string path;         ///< the scene file
    std::string mesh;         ///< resolved mesh path (.obj, .gltf, .glb, .ply)
    bool normalize = false;   ///< centre and scale the largest side to 2 * normalize_bound (spec 3.9)
    float normalize_bound = 0.9f;
    TangentMode tangents = TangentMode::Handed;
    /// What the object is, for the guidance prompt ("a ceramic mug"); empty = from the mesh file
    /// (optimize_run's object_name_of).
    std::string object_name;
    /// Replace the mesh's own UVs by `tdf atlas`'s default atlas (for overlapping, mirrored or
    /// unmapped input UVs; the mesh's albedo texture is re-baked onto the new atlas).
    bool uv_reunwrap = false;
    std::string albedo_source = "mesh";  ///< mesh | image | vertex_colors | constant
    std::string albedo_image;            ///< resolved path, for albedo_source "image"
    Vec3f albedo_color{0.5f, 0.5f, 0.5f};  ///< for "constant"
    std::vector<std::string> tactile_images;  ///< resolved paths; the first is rendered
    std::string label_map;               ///< resolved path or empty
    int width = 512;
    int height = 512;
    float ssaa = 1.f;
    std::string shading = "visualizer";  ///< training | visualizer (checked by the renderer)
    std::string renderer = "ray";        ///< ray | raster: the visibility producer
    bool antialias = false;              ///< dr.antialias; default true for raster, false for ray
    Vec3f background{1, 1, 1};
    std::string color_space = "raw";  ///< raw (the reference) | srgb (glTF viewers), shading.h ColorSpace
    std::vector<std::string> passes = {"lambertian", "albedo", "mask"};  ///< checked by the renderer
    std::uint64_t seed = 0;
    ViewsSpec views;
    LightSpec light;
    PartsSpec parts;  ///< empty unless the scene has a "parts" section
    /// Raw JSON of the sections owned by other modules (optimize, tactile_layout, guidance, export).
    std::map<std::string, Json> sections;

    /// Every setting with defaults filled in and paths resolved, plus the raw sections: what
    /// `tdf render` writes to resolved_scene.json.
    Json to_json() const;
};

/// The top-level sections kept raw for other modules.
const std::vector<std::string>& foreign_scene_sections();

/// Loads `path` with its parents, applies `overrides`, and validates it. Throws tdf::Error with
/// one line naming the file and key on any problem.
SceneDescription load_scene(const std::string& path, const std::vector<std::string>& overrides = {});
/// Parses an already merged scene JSON; `path` names it in messages and anchors relative paths.
SceneDescription parse_scene(const Json& json, const std::string& path);

}  // namespace tdf
