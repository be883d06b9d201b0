#pragma once
/// Multi-part segmentation (docs/multi-part-textures.md): which part of a multi-part scene each
/// face and each atlas texel belongs to, from one of the `parts.source` kinds:
///
/// - `mesh`: the input's structure (TriangleMesh::face_groups), keyed by `material`, `object`,
///   `group` (OBJ usemtl / o / g; glTF material / node / mesh name) or `primitive` (one region
///   per FaceGroup, named "<group index>").
/// - `label_image`: an image in the mesh's own UV space whose colours are the parts; regions are
///   named "#rrggbb". The image must have the size of the mesh's albedo texture when it has one.
/// - `face_labels`: a text file with one label per triangle of the loaded mesh (polygons fanned
///   from their first corner, in file order); `#` starts a comment, blank lines are skipped;
///   a label is any token without spaces. Regions are named by the labels.
/// - `colour`: k-means clusters of the base albedo in CIELAB (colour_segmentation.h), smoothed on
///   the atlas texel grid and over face adjacency; regions are named "0", "1", ... by decreasing
///   area.
/// - `external`: a user program (external_segmentation.h); regions are named by mask index.
///
/// Regions are then matched to parts by PartSpec::select (see PartsSpec).
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/config.h>
#include <tdf/mesh/triangle_mesh.h>
#include <tdf/render/renderer.h>
#include <tdf/scene/scene_file.h>

#include <string>
#include <vector>

namespace tdf {

/// One region the source found, before matching to parts.
struct PartRegion {
    std::string name;     ///< see the source kinds above
    int part = -1;        ///< the part it went to
    double fraction = 0;  ///< share of the surface area (of faces covering a texel), [0, 1]
    bool has_colour = false;
    Vec3f rgb{};  ///< colour and label_image: mean sRGB in [0, 1] (colour) or the key colour
    Vec3f lab{};  ///< colour: mean CIELAB
};

struct PartSegmentation {
    std::vector<std::string> part_names;
    std::vector<int> face_part;  ///< per face of the mesh, in [0, part count)
    int size = 0;                ///< side of the texel raster
    /// Per atlas texel (index i * size + j, UvRaster convention), the part, or -1 for texels no
    /// face covers (gutter and background).
    std::vector<int> texel_part;
    std::vector<PartRegion> regions;
    std::vector<double> part_fraction;  ///< share of the surface area per part (texels weighted by area)
    std::vector<double> silhouette;     ///< colour with k = 0: mean silhouette for K = 2..k_max
    int distinct_colours = 0;           ///< colour: distinct 8-bit colours in the albedo
    double seconds = 0;                 ///< wall time of segment_parts

    std::size_t part_count() const { return part_names.size(); }
    /// The coverage report (`<name>_parts.json`): parts with their texel counts and fractions,
    /// the source's regions (with mean colours for `colour`), timing.
    Json report(const PartsSpec& spec) const;
};

/// Inputs of segment_parts. `mesh` is the loaded (possibly normalised) mesh whose UVs the label
/// image and albedo texture use; `atlas` is the mesh whose UVs the trained maps use (the same
/// faces, e.g. build_atlas(mesh); may be `mesh` itself); `material` gives the base albedo.
struct PartSegmentationInput {
    const TriangleMesh* mesh = nullptr;
    const TriangleMesh* atlas = nullptr;
    const SurfaceMaterial* material = nullptr;
    int size = 1024;         ///< texel raster side (the trained maps' size), [16, 16384]
    std::uint64_t seed = 0;  ///< colour clustering
    std::string where;       ///< names the scene in messages, e.g. "scenes/x.json: parts"
    /// external: folder for the call files (default: the system temp folder)
    std::string work_folder;
};

/// Runs the source and matches its regions to the parts. Throws tdf::Error with one line naming
/// the key on bad input: a part that gets no faces, regions no part selects (without a part that
/// takes the rest), a select naming a region that does not exist, K larger than the colours
/// present, a label image of the wrong size, a face label file with the wrong line count.
PartSegmentation segment_parts(const PartsSpec& spec, const PartSegmentationInput& input);

/// The surface albedo at barycentric `b` of face `f` (texture sampled bilinearly at the
/// interpolated UV, vertex colours interpolated, or the constant), sRGB in [0, 1].
Vec3f albedo_at(const TriangleMesh& mesh, const SurfaceMaterial& material, int face, Vec3f b);

/// Per-texel labels from per-face labels through the atlas raster (centre-covered and partial
/// texels both, see add_partial_texels): -1 where no face touches the texel.
std::vector<int> texel_labels_from_faces(const UvRaster& raster, const std::vector<int>& face_label);

/// Per-face labels from per-texel labels: the most frequent label among the texels the face
/// covers; faces covering no texel take the label their neighbours (sharing an edge) hold most,
/// iterated; faces still unlabelled (isolated) get `fallback`.
std::vector<int> face_labels_from_texels(const TriangleMesh& mesh, const UvRaster& raster,
                                         const std::vector<int>& texel_label, int fallback = 0);

/// Face adjacency over shared edges (positions welded by index), weighted by edge length.
std::vector<std::vector<std::pair<int, float>>> face_adjacency(const TriangleMesh& mesh);

}  // namespace tdf
