#pragma once
/// Rasterizing a mesh's UV layout: which triangle covers each texel, and where inside it.
/// The texture-space counterpart of a render's G-buffer; bakes (colours, the texture field)
/// loop over its texels.
#include <tdf/core/image.h>
#include <tdf/core/vec.h>
#include <tdf/mesh/triangle_mesh.h>

#include <vector>

namespace tdf {

/// The UV layout of a mesh rasterized at texel centres onto a `size` x `size` image.
///
/// Texel (row i, column j), stored at index `i * size + j`, has its centre at
/// u = (j + 0.5) / size, v = 1 - (i + 0.5) / size: row 0 is the top of the image and our UVs
/// are v-up (OBJ convention), which is the reference's UV bake with v' = 1 - v (spec 1.5).
struct UvRaster {
    int size = 0;
    /// Per texel: the face index covering its centre, or -1 when none does.
    std::vector<int> triangle;
    /// Per texel: barycentric weights of the centre for corners 0, 1, 2 of that face (they
    /// weight `triangles[f][k]` and `uv_triangles[f][k]` alike); (0,0,0) when empty.
    std::vector<Vec3f> barycentric;

    std::size_t texel_count() const { return triangle.size(); }
    /// Number of covered texels.
    std::size_t covered_count() const;
};

/// Rasterizes the mesh's UV triangles at texel centres (see UvRaster for the convention).
/// Edges follow a top-left fill rule, so a centre on an edge shared by two triangles belongs to
/// exactly one of them; faces are drawn in index order and, where UV triangles overlap, the
/// highest face index wins (deterministic). Zero-area UV triangles cover nothing.
/// Throws tdf::Error when the mesh has no UVs or `size` is not in [1, 16384].
UvRaster rasterize_uv(const TriangleMesh& mesh, int size);

/// Extends `raster` to the texels that a UV triangle overlaps without covering their centre
/// (chart borders, and charts smaller than a texel), so bakes put true surface values there
/// instead of leaving them to gutter dilation: each such texel, if still empty, goes to the
/// lowest-index face touching it, with the barycentrics of the point of that face nearest to the
/// texel centre (on its border). Zero-area UV triangles are skipped. Deterministic.
void add_partial_texels(const TriangleMesh& mesh, UvRaster& raster);

/// Interpolates a per-vertex attribute (indexed like `mesh.positions`) at every covered texel
/// into a `size` x `size` image with 3 channels; empty texels get `background`.
Image interpolate_vertex_attribute(const TriangleMesh& mesh, const UvRaster& raster,
                                   const std::vector<Vec3f>& attribute, Vec3f background = {});

/// Bilinear lookup of `image` at (u, v) in OBJ convention (v up), texel centres at
/// ((j + 0.5) / width, 1 - (i + 0.5) / height), clamped to the edge texels (no wrap); a
/// non-finite UV reads UV (0, 0). sample_bilinear_uv(image, uv, Addressing::Clamp, out) of
/// core/image_ops.h. Writes `image.channels()` values to `out`.
void sample_bilinear(const Image& image, Vec2f uv, float* out);

}  // namespace tdf
