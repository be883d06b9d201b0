// Part segmentation: every parts source against known ground truth on a procedural sphere, the
// shipped two-part scene (label accuracy >= 98 %), and one clear line per bad input.
#include <tdf/atlas/gutter.h>
#include <tdf/atlas/uv_raster.h>
#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/colour_segmentation.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/render/scene_assets.h>
#include <tdf/scene/procedural_mesh.h>

#include "common/spot_truth.h"
#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace tdf;

namespace {

// Ground truth of the sphere: part 0 above a wavy line (as tools/make_two_part_scene.cpp).
std::vector<int> truth(const TriangleMesh& mesh) {
    std::vector<int> part(mesh.triangles.size());
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
        const Vec3i& t = mesh.triangles[f];
        const Vec3f c = (mesh.positions[std::size_t(t.x)] + mesh.positions[std::size_t(t.y)] +
                         mesh.positions[std::size_t(t.z)]) *
                        (1.f / 3.f);
        part[f] = c.y > 0.12f + 0.18f * std::sin(3.f * std::atan2(c.x, c.z)) ? 0 : 1;
    }
    return part;
}

PartsSpec two_parts(const std::string& kind) {
    PartsSpec spec;
    spec.source.kind = kind;
    PartSpec a, b;
    a.name = "cap";
    b.name = "base";
    a.tactile_images = b.tactile_images = {"unused.png"};
    spec.parts = {a, b};
    return spec;
}

double texel_accuracy(const std::vector<int>& got, const std::vector<int>& want) {
    std::size_t total = 0, right = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
        if (want[i] < 0) continue;
        ++total;
        right += got[i] == want[i];
    }
    return total ? double(right) / double(total) : 0.0;
}

// The error segment_parts throws, which must be one line (README "Errors").
std::string error_of(const PartsSpec& spec, const PartSegmentationInput& in) {
    try {
        segment_parts(spec, in);
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        return message;
    }
    return "(no error)";
}

// A sphere whose albedo texture paints the ground truth: green cap, terracotta base, with noise.
struct PaintedSphere {
    TriangleMesh mesh = make_uv_sphere(0.8f, 48, 24);
    std::vector<int> part = truth(mesh);
    MipTexture albedo;
    SurfaceMaterial material;
    std::vector<int> texel_truth;  // at 256

    PaintedSphere() {
        const UvRaster raster = rasterize_uv(mesh, 128);
        Image image(128, 128, 3, 0.5f);
        for (std::size_t i = 0; i < raster.texel_count(); ++i) {
            const int f = raster.triangle[i];
            if (f < 0) continue;
            const float n = 0.05f * std::sin(float(i) * 12.9898f);
            const Vec3f c = part[std::size_t(f)] == 0 ? Vec3f{0.25f + n, 0.5f + n, 0.22f}
                                                      : Vec3f{0.7f + n, 0.4f, 0.26f + n};
            for (int k = 0; k < 3; ++k) image.data()[i * 3 + std::size_t(k)] = c[k];
        }
        albedo = MipTexture(image);
        material.albedo_source = SurfaceMaterial::AlbedoSource::Texture;
        material.albedo = &albedo;
    }
    PartSegmentationInput input(int size = 128) const {
        PartSegmentationInput in;
        in.mesh = &mesh;
        in.atlas = &mesh;
        in.material = &material;
        in.size = size;
        in.where = "test.json: parts";
        return in;
    }
    std::vector<int> truth_texels(int size) const {
        UvRaster raster = rasterize_uv(mesh, size);
        add_partial_texels(mesh, raster);
        return texel_labels_from_faces(raster, part);
    }
};

}  // namespace

TEST(ColourSegmentation, LabMatchesKnownValues) {
    const Vec3f white = srgb_to_lab({1, 1, 1});
    EXPECT_NEAR(white.x, 100.f, 0.01f);
    EXPECT_NEAR(white.y, 0.f, 0.01f);
    EXPECT_NEAR(white.z, 0.f, 0.01f);
    const Vec3f red = srgb_to_lab({1, 0, 0});  // CIE reference values for sRGB red (D65)
    EXPECT_NEAR(red.x, 53.24f, 0.05f);
    EXPECT_NEAR(red.y, 80.09f, 0.1f);
    EXPECT_NEAR(red.z, 67.20f, 0.1f);
    EXPECT_NEAR(srgb_to_lab({0, 0, 0}).x, 0.f, 1e-4f);
}

TEST(ColourSegmentation, ChoosesKAndRejectsKAboveTheColours) {
    std::vector<Vec3f> rgb;
    for (int i = 0; i < 3000; ++i) {
        const float n = 0.04f * std::sin(float(i) * 1.7f);
        rgb.push_back(i % 3 == 0   ? Vec3f{0.8f + n, 0.1f, 0.1f}
                      : i % 3 == 1 ? Vec3f{0.1f, 0.7f + n, 0.1f}
                                   : Vec3f{0.1f, 0.1f, 0.8f + n});
    }
    const std::vector<float> w(rgb.size(), 1.f);
    ColourClusteringOptions o;
    const ColourClustering c = cluster_colours(rgb, w, o, "t");
    ASSERT_EQ(c.clusters.size(), 3u);
    EXPECT_EQ(c.silhouette.size(), 5u);  // K = 2..6
    EXPECT_GT(c.silhouette[1], c.silhouette[0]);
    // Samples of one colour share one cluster.
    for (std::size_t i = 3; i < rgb.size(); ++i) EXPECT_EQ(c.label[i], c.label[i % 3]);
    // K larger than the colours present.
    const std::vector<Vec3f> two = {{1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 1, 0}};
    o.k = 3;
    try {
        cluster_colours(two, std::vector<float>(4, 1.f), o, "scene.json: parts.source");
        ADD_FAILURE() << "k = 3 accepted for 2 colours";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("k is 3 but the albedo has only 2 distinct colour(s)"),
                  std::string::npos)
            << e.what();
    }
    o.k = 0;
    EXPECT_THROW(
        cluster_colours(std::vector<Vec3f>(5, Vec3f{0.2f, 0.2f, 0.2f}), std::vector<float>(5, 1.f), o, "t"),
        Error);
}

TEST(ColourSegmentation, MajoritySmoothingRemovesIsolatedLabels) {
    // A path 0-1-2-3-4 labelled 0 0 1 0 0: the middle flips; -1 stays.
    std::vector<std::vector<std::pair<int, float>>> n(6);
    for (int i = 0; i + 1 < 5; ++i) {
        n[std::size_t(i)].push_back({i + 1, 1.f});
        n[std::size_t(i + 1)].push_back({i, 1.f});
    }
    std::vector<int> label = {0, 0, 1, 0, 0, -1};
    majority_smooth(label, n, 3);
    EXPECT_EQ(label, (std::vector<int>{0, 0, 0, 0, 0, -1}));
}

TEST(PartSegmentation, MeshGroupsByMaterialObjectAndGroup) {
    PaintedSphere s;
    s.mesh.face_groups = {FaceGroup{"plant", "g1", "green"}, FaceGroup{"pot", "g1", "clay"}};
    s.mesh.face_group = s.part;
    PartsSpec spec = two_parts("mesh");
    spec.parts[0].select = {"green"};
    spec.parts[1].select = {"clay"};
    PartSegmentation seg = segment_parts(spec, s.input());
    EXPECT_EQ(seg.face_part, s.part);
    EXPECT_EQ(texel_accuracy(seg.texel_part, s.truth_texels(128)), 1.0);
    EXPECT_NEAR(seg.part_fraction[0] + seg.part_fraction[1], 1.0, 1e-9);
    // By object, the base taking the rest.
    spec.source.key = "object";
    spec.parts[0].select = {"plant"};
    spec.parts[1].select.clear();
    EXPECT_EQ(segment_parts(spec, s.input()).face_part, s.part);
    // By group: one region for two parts.
    spec.source.key = "group";
    spec.parts[0].select.clear();
    EXPECT_NE(error_of(spec, s.input()).find("found 1 regions ('g1') but there are 2 parts"),
              std::string::npos)
        << error_of(spec, s.input());
    // A select naming no region, and a part left with no faces.
    spec.source.key = "material";
    spec.parts[0].select = {"leaf"};
    EXPECT_NE(error_of(spec, s.input()).find("test.json: parts.list[0].select: 'leaf' is not a region"),
              std::string::npos)
        << error_of(spec, s.input());
    spec.parts[0].select = {"green", "clay"};
    EXPECT_NE(error_of(spec, s.input()).find("part 'base' has no faces"), std::string::npos)
        << error_of(spec, s.input());
    // Without groups the mesh source says so.
    s.mesh.face_groups.clear();
    s.mesh.face_group.clear();
    EXPECT_NE(error_of(two_parts("mesh"), s.input()).find("has no objects, groups or materials"),
              std::string::npos);
}

TEST(PartSegmentation, FaceLabelFile) {
    PaintedSphere s;
    const std::string path = test::scratch_dir() + "/labels.txt";
    {
        std::ofstream out(path);
        out << "# one label per triangle\n\n";
        for (int p : s.part) out << (p == 0 ? "cap" : "base") << "  # comment\n";
    }
    PartsSpec spec = two_parts("face_labels");
    spec.source.file = path;
    spec.parts[0].select = {"cap"};
    spec.parts[1].select = {"base"};
    EXPECT_EQ(segment_parts(spec, s.input()).face_part, s.part);
    // Wrong count, two labels on a line.
    std::ofstream(test::scratch_dir() + "/short.txt") << "cap\nbase\n";
    spec.source.file = test::scratch_dir() + "/short.txt";
    EXPECT_NE(error_of(spec, s.input()).find("2 labels for the mesh's 2208 triangles"), std::string::npos)
        << error_of(spec, s.input());
    std::ofstream(test::scratch_dir() + "/two.txt") << "cap base\n";
    spec.source.file = test::scratch_dir() + "/two.txt";
    EXPECT_NE(error_of(spec, s.input()).find("two.txt:1: one label per line"), std::string::npos);
}

TEST(PartSegmentation, LabelImageInTheMeshUvSpace) {
    PaintedSphere s;
    // Paint the labels at the albedo's size: red cap, green base, with anti-aliased edge colours.
    const UvRaster raster = rasterize_uv(s.mesh, 128);
    Image labels(128, 128, 3, 0.f);
    for (std::size_t i = 0; i < raster.texel_count(); ++i) {
        const int f = raster.triangle[i];
        if (f >= 0) labels.data()[i * 3 + (s.part[std::size_t(f)] == 0 ? 0 : 1)] = 1.f;
    }
    dilate_gutter(labels, raster.triangle, 4);       // painted past the chart borders, as a label image is
    labels.at(5, 5, 0) = labels.at(5, 5, 1) = 0.5f;  // one blended texel
    const std::string path = test::scratch_dir() + "/labels.png";
    write_png(path, labels);
    PartsSpec spec = two_parts("label_image");
    spec.source.image = path;
    spec.parts[0].select = {"#FF0000"};
    spec.parts[1].select = {"#00ff00"};
    const PartSegmentation seg = segment_parts(spec, s.input(256));
    const double accuracy = texel_accuracy(seg.texel_part, s.truth_texels(256));
    EXPECT_GE(accuracy, 0.99) << accuracy;
    std::size_t wrong_faces = 0;
    for (std::size_t f = 0; f < s.part.size(); ++f) wrong_faces += seg.face_part[f] != s.part[f];
    EXPECT_LE(wrong_faces, s.part.size() / 100);
    // Wrong size: not the albedo's 128 x 128.
    write_png(test::scratch_dir() + "/small.png", Image(64, 64, 3, 1.f));
    spec.source.image = test::scratch_dir() + "/small.png";
    EXPECT_NE(error_of(spec, s.input()).find("parts.source.image: '"), std::string::npos);
    EXPECT_NE(error_of(spec, s.input()).find("is 64x64 but the mesh's albedo texture is 128x128"),
              std::string::npos)
        << error_of(spec, s.input());
}

TEST(PartSegmentation, ColourClustersTheAlbedoAndReportsThem) {
    PaintedSphere s;
    PartsSpec spec = two_parts("colour");  // no select: clusters in order of area
    const PartSegmentation seg = segment_parts(spec, s.input(256));
    // Which cluster is the cap: the greener one.
    ASSERT_EQ(seg.regions.size(), 2u);
    const int green = seg.regions[0].rgb.y > seg.regions[0].rgb.x ? 0 : 1;
    std::vector<int> want = s.truth_texels(256);
    for (int& l : want)
        if (l >= 0) l = l == 0 ? green : 1 - green;
    const double accuracy = texel_accuracy(seg.texel_part, want);
    EXPECT_GE(accuracy, 0.98) << accuracy;
    const Json report = seg.report(spec);
    EXPECT_EQ(report["regions"].size(), 2u);
    EXPECT_TRUE(report["regions"][0].contains("hex"));
    EXPECT_TRUE(report.contains("silhouette_by_k"));
    EXPECT_NEAR(
        report["regions"][0]["fraction"].get<double>() + report["regions"][1]["fraction"].get<double>(),
        1.0,
        1e-9);
    // K larger than the colours present: a constant albedo has one.
    spec.source.k = 3;
    SurfaceMaterial grey;
    PartSegmentationInput in = s.input();
    in.material = &grey;
    EXPECT_NE(error_of(spec, in).find(
                  "test.json: parts.source: k is 3 but the albedo has only 1 distinct colour(s)"),
              std::string::npos)
        << error_of(spec, in);
}

TEST(PartSegmentation, ExternalProgramThroughTheFileProtocol) {
    PaintedSphere s;
    PartsSpec spec = two_parts("external");
    spec.source.external = Json{{"command", Json::array({TDF_TEST_SEGMENTER, "{request}"})},
                                {"views", 6},
                                {"resolution", 128},
                                {"elevations", {-35, 35}}};
    const PartSegmentation seg = segment_parts(spec, s.input(128));
    std::size_t right = 0;
    for (std::size_t f = 0; f < s.part.size(); ++f) right += seg.face_part[f] == s.part[f];
    const double accuracy = double(right) / double(s.part.size());
    EXPECT_GE(accuracy, 0.97) << accuracy;
    spec.source.external["command"] = Json::array({TDF_TEST_SEGMENTER, "--fail", "{request}"});
    EXPECT_NE(error_of(spec, s.input()).find("failed (exit 3"), std::string::npos)
        << error_of(spec, s.input());
    EXPECT_NE(error_of(spec, s.input()).find("failing on purpose"), std::string::npos);
    spec.source.external["command"] = Json::array({TDF_TEST_SEGMENTER, "--skip", "{request}"});
    EXPECT_NE(error_of(spec, s.input()).find("did not write"), std::string::npos)
        << error_of(spec, s.input());
}

TEST(PartSegmentation, ShippedTwoPartSceneColourAccuracy) {
    // scenes/two_part_sphere: labels from colour alone vs the ground truth (labels.txt).
    const std::string scene = test::source_dir() + "/scenes/two_part_sphere/scene.json";
    const SceneDescription description = load_scene(scene);
    const auto assets = load_scene_assets(description);
    PartSegmentationInput in;
    in.mesh = in.atlas = &assets->mesh;
    in.material = &assets->material;
    in.size = 512;
    in.where = scene + ": parts";
    const PartSegmentation colour = segment_parts(description.parts, in);
    PartsSpec truth_spec = description.parts;
    truth_spec.source.kind = "face_labels";
    truth_spec.source.file = test::source_dir() + "/scenes/two_part_sphere/labels.txt";
    truth_spec.parts[0].select = {"cap"};
    truth_spec.parts[1].select = {"base"};
    const PartSegmentation truth = segment_parts(truth_spec, in);
    const double accuracy = texel_accuracy(colour.texel_part, truth.texel_part);
    std::printf("two_part_sphere colour segmentation: %.4f of %zu foreground texels right, K = %zu, %.2f s\n",
                accuracy,
                std::size_t(std::count_if(
                    truth.texel_part.begin(), truth.texel_part.end(), [](int l) { return l >= 0; })),
                colour.regions.size(),
                colour.seconds);
    EXPECT_GE(accuracy, 0.98);
    // The mesh's own materials and the label image are the ground truth exactly.
    PartsSpec mesh_spec = truth_spec;
    mesh_spec.source.kind = "mesh";
    EXPECT_EQ(segment_parts(mesh_spec, in).texel_part, truth.texel_part);
    PartsSpec image_spec = truth_spec;
    image_spec.source.kind = "label_image";
    image_spec.source.image = test::source_dir() + "/scenes/two_part_sphere/label_image.png";
    image_spec.parts[0].select = {"#ff0000"};
    image_spec.parts[1].select = {"#00ff00"};
    EXPECT_GE(texel_accuracy(segment_parts(image_spec, in).texel_part, truth.texel_part), 0.995);
}

TEST(PartSegmentation, SpotPatchesFromColourOnTheRealMesh) {
    // scenes/spot_parts: the cow's dark patches from colour alone (K = 6, cluster 3) against an
    // independent rule on the same texture: texels darker than L* = 36 are patches.
    TDF_REQUIRE_SHARED_DATA("meshes/spot/spot_triangulated.obj");
    const std::string scene = test::source_dir() + "/scenes/spot_parts/scene.json";
    const SceneDescription description = load_scene(scene);
    const auto assets = load_scene_assets(description);
    PartSegmentationInput in;
    in.mesh = in.atlas = &assets->mesh;
    in.material = &assets->material;
    in.size = 512;
    in.where = scene + ": parts";
    const PartSegmentation seg = segment_parts(description.parts, in);
    const std::vector<int> dark = test::spot_dark_patches(assets->mesh, assets->material, 512);
    const double accuracy = texel_accuracy(seg.texel_part, dark);
    std::printf(
        "spot patches: %.4f of foreground texels agree with the L* < 36 rule, patches %.2f %%, %.2f s\n",
        accuracy,
        100.0 * seg.part_fraction[1],
        seg.seconds);
    EXPECT_GE(accuracy, 0.98);
    EXPECT_GT(seg.part_fraction[1], 0.05);
    EXPECT_LT(seg.part_fraction[1], 0.2);
}

TEST(PartSegmentation, SameColourSegmentationOnOneAndTwoThreads) {
    PaintedSphere s;
    const PartsSpec spec = two_parts("colour");
    PartSegmentation one, two;
    {
        ThreadLimit limit(1);
        one = segment_parts(spec, s.input(256));
    }
    {
        ThreadLimit limit(2);
        two = segment_parts(spec, s.input(256));
    }
    EXPECT_EQ(one.texel_part, two.texel_part);
    EXPECT_EQ(one.face_part, two.face_part);
    ASSERT_EQ(one.regions.size(), two.regions.size());
    EXPECT_EQ(one.regions[0].rgb.x, two.regions[0].rgb.x);
}
