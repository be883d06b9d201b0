#pragma once
/// Baking the texture field into UV maps (spec 1.5, with our choices): the field is evaluated at
/// the surface point behind every covered texel centre of the atlas, and empty texels near
/// charts are filled by dilation across seams (instead of the reference's slow, smearing Telea
/// inpainting) so bilinear and mip sampling never read the background.
#include <tdf/atlas/uv_raster.h>
#include <tdf/field/texture_field.h>
#include <tdf/mesh/triangle_mesh.h>

namespace tdf {

struct BakedMaps {
    Image albedo;         ///< RGB in (0, 1)
    Image tactile_normal; ///< tangent-space unit normals in [-1, 1], OpenGL (green = +v)
    UvRaster raster;      ///< which triangle covers each texel (-1 = empty before dilation)
};

/// Bakes `field` over `mesh`'s UV atlas at size x size texels, dilating `gutter` texels.
/// Texels beyond the gutter stay (0.5 grey, flat normal (0,0,1)).
BakedMaps bake_field(const TextureField& field, const TriangleMesh& mesh, int size, int gutter);

/// A tangent-space normal map in [-1, 1] as colours in [0, 1]: (n + 1) / 2, n renormalised
/// first (spec 1.5 step 6). Write with Quantize::Truncate for the reference's 8-bit encoding.
Image encode_normal_map(const Image& normals);

}  // namespace tdf
