#pragma once
/// Bakes into texture space: vertex colours -> albedo map, and an old texture re-sampled onto a
/// new UV layout of the same surface. Both finish with gutter dilation over the whole map
/// (dilate_gutter with texels = 0), so bilinear and mip-mapped sampling never reach background.
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/image.h>
#include <tdf/mesh/triangle_mesh.h>

namespace tdf {

/// A `size` x `size` RGB map of the mesh's per-vertex colours, interpolated barycentrically at
/// every texel centre its UV layout covers (rasterize_uv) and at the nearest surface point for
/// texels the layout only partly covers (add_partial_texels), then dilated to fill the rest.
/// Throws tdf::Error when the mesh has no UVs or no vertex colours.
Image bake_vertex_colors(const TriangleMesh& mesh, int size);

/// Re-bakes `texture`, laid out by `source`'s UVs, onto `target`'s UVs: each covered (or partly
/// covered) texel of the target takes the bilinear sample of `texture` at the same surface point (same face,
/// same barycentrics) through the source UVs. `source` and `target` must share faces (same count and position
/// indices, as build_atlas guarantees). Output has the texture's channel count. Throws tdf::Error when the
/// faces differ, either mesh lacks UVs, or the texture is empty.
Image rebake_texture(const TriangleMesh& source, const Image& texture, const TriangleMesh& target, int size);

}  // namespace tdf
