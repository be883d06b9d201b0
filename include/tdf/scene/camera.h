#pragma once
/// Pinhole (perspective) and orthographic cameras with the reference's conventions (spec 2):
/// world Y up, OpenGL look-at (the camera looks along its -Z; `back` = camera +Z points from the
/// target to the camera), image row 0 = top, pixel (i, j) centred at (j + 0.5, i + 0.5).
///
/// Clipping is planar as in the rasterizer (spec 2.2): a surface is visible when its camera-space
/// z lies in [-far_plane, -near_plane]. generate_ray() builds rays whose direction has camera-space
/// z = -1, so the ray parameter t IS the depth -z_cam and [near_plane, far_plane] is the t range.
#include <tdf/core/vec.h>

namespace tdf {

/// A row-major 4x4 matrix: m[row][column], acting on column vectors.
struct Mat4f {
    float m[4][4] = {};
    static Mat4f identity();
    Vec4f operator*(Vec4f v) const;
    Mat4f operator*(const Mat4f& b) const;
};

/// A ray o + t d, visible for t in [tnear, tfar]. `direction` is not normalised (see above).
struct Ray {
    Vec3f origin;
    Vec3f direction;
    float tnear = 0;
    float tfar = 0;
};

struct Camera {
    enum class Kind { Perspective, Orthographic };

    Kind kind = Kind::Perspective;
    Vec3f position{0, 0, 1};  ///< world-space camera centre
    Vec3f right{1, 0, 0};     ///< camera +X in world space (unit)
    Vec3f up{0, 1, 0};        ///< camera +Y in world space (unit)
    Vec3f back{0, 0, 1};      ///< camera +Z in world space (unit), from target to camera
    float fovy_degrees = 49.1f;  ///< perspective: full vertical field of view
    float half_extent = 0.075f;  ///< orthographic: half height of the view window, world units
    float near_plane = 0.01f;    ///< planar clipping distance along -back (spec 2.2)
    float far_plane = 100.f;
    int width = 512;
    int height = 512;
    /// Row 0 shows camera-DOWN instead of camera-up. The reference's orthographic patch renders
    /// are stored this way (its ortho matrix lacks the y negation, spec 2.2 / 13.13); tdf renders
    /// upright by default and sets this only for reference parity.
    bool flip_rows = false;

    /// Orbit camera about `target` (spec 2.1): position = target + r (cos e sin a, -sin e,
    /// cos e cos a). Degrees. POSITIVE elevation puts the camera BELOW the equator; azimuth 0 is
    /// on +Z, +90 on +X. Perspective, aspect width/height.
    static Camera orbit(float elevation_deg, float azimuth_deg, float radius, float fovy_deg, int width,
                        int height, Vec3f target = {});

    /// OpenGL look-at with world up (0,1,0): back = normalize(position - target),
    /// right = normalize(up_w x back), up = back x right. When back is (nearly) parallel to Y the
    /// frame is degenerate in the reference; tdf then uses up_w = (0, 0, -sign(back.y)), which is
    /// the limit of the reference frame as the view direction tilts toward +Z (a camera above
    /// the object sees +X to the right and -Z up, like a top view).
    static Camera look_at(Vec3f position, Vec3f target, Kind kind, int width, int height);

    /// Tactile patch camera (spec 2.4): orthographic, centred at surface_point + distance *
    /// unit_normal, looking along -unit_normal, window 2 half_extent wide (0.15 units by default).
    /// Upright images (row 0 = camera up) unless `flip_rows` is set afterwards.
    static Camera tactile_patch(Vec3f surface_point, Vec3f unit_normal, int width, int height,
                                float distance = 0.1f, float half_extent = 0.075f);

    float aspect() const { return float(width) / float(height); }
    /// tan(fovy / 2).
    float tan_half_fovy() const;

    /// The ray through image position (px, py) in pixels (x right, y down; the centre of pixel
    /// (i, j) is (j + 0.5, i + 0.5)). Perspective rays start at the camera centre; orthographic
    /// rays start on the camera plane. Direction has camera-space z = -1 (t = depth).
    Ray generate_ray(float px, float py) const;
    /// Derivatives of the ray origin and direction with respect to px and py (constant over the
    /// image for both kinds), for ray differentials.
    void ray_derivatives(Vec3f& dorigin_dpx, Vec3f& dorigin_dpy, Vec3f& ddir_dpx, Vec3f& ddir_dpy) const;

    /// R^T d: a world direction in camera coordinates (x right, y up, z toward the viewer).
    Vec3f world_to_camera_direction(Vec3f d) const;
    /// R d: a camera-space direction in world coordinates.
    Vec3f camera_to_world_direction(Vec3f d) const;
    /// A world point in camera coordinates.
    Vec3f world_to_camera_point(Vec3f p) const;

    /// Camera-to-world pose [[R, position], [0, 0, 0, 1]] with R = [right, up, back] (spec 2.1).
    Mat4f pose_matrix() const;
    /// World-to-camera, inverse(pose).
    Mat4f view_matrix() const;
    /// Projection to nvdiffrast clip space (row 0 of the image = NDC y -1), spec 2.2. Perspective:
    /// the spec's matrix (y negated -> upright). Orthographic: with flip_rows the spec's matrix
    /// (no negation, flipped patch), otherwise the same with y negated (upright).
    Mat4f projection_matrix() const;
};

}  // namespace tdf
