#pragma once
// A small mesh for tests of UV seams and tangent frames: an open cone band around y of `segments`
// quads (radius 1 at y = 0, `top_radius` at y = `height`); quad s has u in [s, s+1] * u_step and
// v in [0, 1] * v_step, and the UV column after the last duplicates nothing, so when
// segments * u_step = 1 the band's cut is a translation seam (u = 0 / u = 1). With `turned_first`,
// segment 0's faces get their own chart instead: the rectangle u_step x v_step at `turned_at`,
// turned a quarter round (its u runs along the band's height), which meets its neighbours at two
// seams that are not translations. On a cone, unlike a cylinder, the faces' dP/du leave the
// vertices' tangent planes at an angle, so frames that average different faces differ.
#include <tdf/mesh/triangle_mesh.h>

namespace tdf::test {

TriangleMesh make_cone_band(int segments, float u_step, float v_step, float height, float top_radius,
                            bool turned_first, Vec2f turned_at = {0, 0});

}  // namespace tdf::test
