#include <gtest/gtest.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/render/renderer.h>
#include <tdf/render/shading.h>
#include <tdf/render/trace.h>
#include <tdf/scene/procedural_mesh.h>

#include <algorithm>
#include <cmath>
#include <set>

using namespace tdf;

namespace {
const std::vector<Pass> kAll = {Pass::Albedo,        Pass::Lambertian,    Pass::Mask,
                                Pass::Depth,         Pass::Normal,        Pass::Tangent,
                                Pass::Uv,            Pass::TactileNormal, Pass::ShadingNormal,
                                Pass::ShadingNormalViewspace, Pass::Label};
}

TEST(Renderer, QuadUnderAPointLightGivesClosedFormLambertian) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    SurfaceMaterial material;
    material.albedo_constant = {0.8f, 0.4f, 0.2f};
    const Renderer renderer(quad, scene, material);
    const Camera cam = Camera::orbit(0, 0, 2, 90, 64, 64);
    const Light light{Light::Kind::Point, {0.5f, -0.3f, 1.2f}, 0.5f};
    const Frame frame = renderer.render(cam, light, kAll);
    const Image& lambert = *frame.find(Pass::Lambertian);
    const GBuffer g = trace_gbuffer(scene, quad, cam);
    double max_error = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const std::size_t i = g.index(x, y);
            if (!g.mask[i]) {
                EXPECT_EQ(lambert.at(x, y, 0), 1.f);  // white background
                continue;
            }
            // Spec 3.4: c (0.5 max(0, n.l) + 0.5), n = +Z, l = normalize(L - p).
            const Vec3f l = safe_normalize(light.vector - g.position[i]);
            const float shade = 0.5f * std::max(0.f, l.z) + 0.5f;
            for (int k = 0; k < 3; ++k)
                max_error = std::max(max_error, double(std::fabs(lambert.at(x, y, k) - material.albedo_constant[k] * shade)));
        }
    EXPECT_LT(max_error, 1e-6);
    // Flat tactile map: the shading normal is the geometric normal, in view space +Z.
    const Image& view = *frame.find(Pass::ShadingNormalViewspace);
    EXPECT_NEAR(view.at(32, 32, 2), 1.f, 1e-6f);
    EXPECT_EQ(view.at(1, 1, 2), 0.f);
    EXPECT_EQ(frame.find(Pass::Label)->at(32, 32, 0), 0.f);
    EXPECT_NEAR(frame.find(Pass::Uv)->at(40, 20, 1), 1.f - g.uv[g.index(40, 20)].y, 1e-6f);
}

TEST(Renderer, SphereUnderADirectionalLightMatchesCosineLaw) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 256, 128);
    const EmbreeScene scene(sphere);
    SurfaceMaterial material;
    material.albedo_constant = {1, 1, 1};
    RenderSettings settings;
    settings.shading = ShadingMode::Visualizer;
    const Renderer renderer(sphere, scene, material, settings);
    const Camera cam = Camera::orbit(0, 0, 3, 50, 96, 96);
    const Vec3f l = orbit_direction(0, 0);  // light from the camera
    const Frame frame = renderer.render(cam, {Light::Kind::Directional, l, 0.1f}, {Pass::Lambertian, Pass::Normal});
    const GBuffer g = trace_gbuffer(scene, sphere, cam);
    double max_error = 0;
    for (std::size_t i = 0; i < g.pixel_count(); ++i) {
        if (!g.mask[i]) continue;
        // Closed form on the exact sphere: n = p / |p|. Faceting makes the interpolated normal
        // differ by O(1/segments^2).
        const Vec3f n = safe_normalize(g.position[i]);
        const float expect = 0.1f + 0.9f * std::max(0.f, dot(n, l));
        max_error = std::max(max_error, double(std::fabs(frame.find(Pass::Lambertian)->data()[3 * i] - expect)));
    }
    EXPECT_LT(max_error, 2e-3);
}

TEST(Renderer, SsaaResizesEveryPassAndMakesCoverageFractional) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 32, 16);
    const EmbreeScene scene(sphere);
    const Renderer renderer(sphere, scene, SurfaceMaterial{});
    const Camera cam = Camera::orbit(0, 0, 3, 49.1f, 50, 40);
    const Frame frame = renderer.render_ssaa(cam, 1.5f, Light{}, {Pass::Mask, Pass::Albedo});
    ASSERT_EQ(frame.images[0].width(), 50);
    ASSERT_EQ(frame.images[1].height(), 40);
    bool fractional = false;
    for (float m : frame.images[0].values()) fractional |= m > 0.f && m < 1.f;
    EXPECT_TRUE(fractional);
}

TEST(Renderer, HandedTangentsFlipTheGreenChannelOnMirroredCharts) {
    // A quad with u mirrored: T = -X, w = -1. A map tilting toward +v (green up) must tilt the
    // shading normal toward +Y in both cases; the reference (w discarded) tilts it to -Y.
    TriangleMesh mirrored = make_quad(1.f);
    for (Vec2f& uv : mirrored.uvs) uv.x = 1.f - uv.x;
    compute_tangents(mirrored, TangentMode::Handed);
    Image map(4, 4, 3);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            map.at(x, y, 0) = 0.f;
            map.at(x, y, 1) = 0.6f;
            map.at(x, y, 2) = 0.8f;
        }
    const MipTexture tactile(map);
    SurfaceMaterial material;
    material.tactile = &tactile;
    const Camera cam = Camera::orbit(0, 0, 2, 90, 16, 16);
    const EmbreeScene scene(mirrored);
    const Frame handed = Renderer(mirrored, scene, material).render(cam, Light{}, {Pass::ShadingNormal});
    EXPECT_NEAR(handed.images[0].at(8, 8, 1), 0.6f, 1e-5f);
    compute_tangents(mirrored, TangentMode::Reference);
    const Frame reference = Renderer(mirrored, scene, material).render(cam, Light{}, {Pass::ShadingNormal});
    EXPECT_NEAR(reference.images[0].at(8, 8, 1), -0.6f, 1e-5f);
}

// Maps with other than three channels (an RGBA albedo, a grey one, an XYZW tactile map) are
// looked up into the tile's planes and read as RGB there: the frame is bit for bit that of the
// same maps cut to (or spread over) three channels, which take the lanes' RGB path.
TEST(Renderer, MapsOfOtherChannelCountsRenderAsTheirRgb) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 32, 16);
    const EmbreeScene scene(sphere);
    constexpr int kSize = 64;
    Image rgba(kSize, kSize, 4), rgb(kSize, kSize, 3), grey(kSize, kSize, 1), grey3(kSize, kSize, 3);
    Image xyzw(kSize, kSize, 4), xyz(kSize, kSize, 3);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const float s = std::sin(0.3f * float(x)), c = std::cos(0.2f * float(y));
            const float colour[4] = {0.5f + 0.4f * s, 0.5f + 0.4f * c, 0.3f, 0.1f * float(x % 7)};
            const Vec3f n = safe_normalize({0.4f * s, 0.4f * c, 1.f});
            for (int k = 0; k < 4; ++k) {
                rgba.at(x, y, k) = colour[k];
                xyzw.at(x, y, k) = k < 3 ? n[k] : 0.7f;
                if (k < 3) rgb.at(x, y, k) = colour[k], xyz.at(x, y, k) = n[k], grey3.at(x, y, k) = colour[1];
            }
            grey.at(x, y, 0) = colour[1];
        }
    const MipTexture t_rgba(rgba), t_rgb(rgb), t_grey(grey), t_grey3(grey3), t_xyzw(xyzw), t_xyz(xyz);
    const Camera cam = Camera::orbit(20, 30, 2.5f, 49.1f, 96, 80);
    const Light light{Light::Kind::Point, {2, 3, 4}, 0.5f};
    const std::vector<Pass> passes = {
        Pass::Albedo, Pass::Lambertian, Pass::TactileNormal, Pass::ShadingNormal};
    const auto render = [&](const MipTexture& albedo, const MipTexture& tactile) {
        SurfaceMaterial material;
        material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
        material.albedo = &albedo;
        material.tactile = &tactile;
        return Renderer(sphere, scene, material).render(cam, light, passes);
    };
    const auto expect_same = [&](const Frame& a, const Frame& b, const char* what) {
        ASSERT_EQ(a.images.size(), b.images.size());
        for (std::size_t k = 0; k < a.images.size(); ++k)
            ASSERT_TRUE(a.images[k].values() == b.images[k].values()) << what << ", pass " << k;
    };
    const Frame reference = render(t_rgb, t_xyz);
    expect_same(render(t_rgba, t_xyz), reference, "RGBA albedo");
    expect_same(render(t_rgb, t_xyzw), reference, "XYZW tactile map");
    expect_same(render(t_grey, t_xyz), render(t_grey3, t_xyz), "grey albedo");
    // The maps were read: the albedo pass holds more than the background and a constant.
    const auto& albedo = reference.find(Pass::Albedo)->values();
    EXPECT_GT(std::set<float>(albedo.begin(), albedo.end()).size(), 100u);
}

TEST(Renderer, BadInputIsAnError) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    SurfaceMaterial material;
    material.albedo_source = SurfaceMaterial::AlbedoSource::VertexColors;
    EXPECT_THROW(Renderer(quad, scene, material), Error);
    const Renderer ok(quad, scene, SurfaceMaterial{});
    Camera cam = Camera::orbit(0, 0, 2, 49.1f, 0, 16);
    cam.width = 0;
    EXPECT_THROW(ok.render(cam, Light{}, {Pass::Mask}), Error);
    EXPECT_THROW(ok.render(Camera::orbit(0, 0, 2, 49.1f, 8, 8), Light{}, {Pass::Mask, Pass::Mask}), Error);
    EXPECT_THROW(parse_pass("albdo"), Error);
}

TEST(Renderer, BitIdenticalForAnyThreadCount) {
    const TriangleMesh sphere = make_uv_sphere(1.f, 64, 32);
    const EmbreeScene scene(sphere);
    Image map(64, 64, 3);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x) {
            const Vec3f n = safe_normalize({std::sin(float(x)), std::cos(float(y)), 2.f});
            for (int c = 0; c < 3; ++c) map.at(x, y, c) = n[c];
        }
    const MipTexture tactile(map);
    SurfaceMaterial material;
    material.tactile = &tactile;
    const Renderer renderer(sphere, scene, material);
    const Camera cam = Camera::orbit(-10, 40, 3, 49.1f, 77, 61);
    const Light light{Light::Kind::Point, {1, 2, 3}, 0.5f};
    const std::vector<Pass> passes = {Pass::Lambertian, Pass::ShadingNormalViewspace, Pass::Mask};
    Frame one, two;
    {
        ThreadLimit limit(1);
        one = renderer.render_ssaa(cam, 1.37f, light, passes);
    }
    {
        ThreadLimit limit(2);
        two = renderer.render_ssaa(cam, 1.37f, light, passes);
    }
    for (std::size_t k = 0; k < passes.size(); ++k) EXPECT_EQ(one.images[k].values(), two.images[k].values());
}

TEST(Renderer, SrgbColorSpaceShadesInLinearLightAndKeepsTheAlbedoPass) {
    const TriangleMesh quad = make_quad(1.f);
    const EmbreeScene scene(quad);
    SurfaceMaterial material;
    material.albedo_constant = {0.5f, 0.25f, 0.75f};
    const Light light{Light::Kind::Directional, normalize_or_zero({0.f, 1.f, 1.f}), 0.1f};
    const Camera cam = Camera::orbit(0, 0, 2, 90, 16, 16);
    const float shade = 0.1f + 0.9f * std::sqrt(0.5f);
    for (const ColorSpace space : {ColorSpace::Raw, ColorSpace::Srgb}) {
        RenderSettings settings;
        settings.color_space = space;
        const Renderer renderer(quad, scene, material, settings);
        const Frame frame = renderer.render(cam, light, {Pass::Albedo, Pass::Lambertian});
        const Vec3f expected = lit_color(material.albedo_constant, shade, space);
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(frame.images[1].at(8, 8, k), expected[k], 1e-5f) << color_space_name(space);
            EXPECT_EQ(frame.images[0].at(8, 8, k), material.albedo_constant[k]) << "the albedo pass is the stored colour";
        }
    }
    // The two differ (sRGB lightens the shaded mid-tones).
    EXPECT_GT(lit_color(material.albedo_constant, shade, ColorSpace::Srgb).x,
              lit_color(material.albedo_constant, shade, ColorSpace::Raw).x + 0.05f);
}
