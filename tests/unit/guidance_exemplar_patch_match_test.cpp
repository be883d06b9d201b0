#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/guidance/image_filters.h>
#include <tdf/tactile/relief_statistics.h>

#include "common/test_paths.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace tdf {
namespace {

void set_normal(Image& image, int x, int y, Vec3f n) {
    n = safe_normalize(n);
    image.at(x, y, 0) = n.x, image.at(x, y, 1) = n.y, image.at(x, y, 2) = n.z;
}

/// A synthetic tactile exemplar: a grid of round bumps (period 8 px) plus a ridge every 24 px,
/// so it is not symmetric under 90-degree rotations.
Image bump_exemplar(int size) {
    Image e(size, size, 3);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float u = float(x % 8) - 3.5f, v = float(y % 8) - 3.5f;
            const float ridge = (x % 24) < 3 ? 0.8f : 0.0f;
            set_normal(e, x, y, Vec3f(0.25f * u + ridge, -0.25f * v, 1.0f));
        }
    return e;
}

/// The 90-degree counter-clockwise rotation of a normal map: picture and vectors.
Image rotate90(const Image& image) {
    const int w = image.width(), h = image.height();
    Image out(h, w, 3);
    for (int y = 0; y < w; ++y)
        for (int x = 0; x < h; ++x) {
            // Output (x, y) shows source (w - 1 - y, x); vector (nx, ny) -> (-ny, nx).
            const float* s = image.pixel(w - 1 - y, x);
            set_normal(out, x, y, Vec3f(-s[1], s[0], s[2]));
        }
    return out;
}

Image crop(const Image& image, int x0, int y0, int w, int h) {
    Image out(w, h, image.channels());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < image.channels(); ++c) out.at(x, y, c) = image.at(x0 + x, y0 + y, c);
    return out;
}

/// Smooth, nearly flat normals: what a field initialised without tactile detail renders.
Image smooth_normals(int size, std::uint64_t seed) {
    Image n(size, size, 3);
    Rng rng(seed);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            set_normal(n, x, y, Vec3f(0.3f * rng.normal(), 0.3f * rng.normal(), 1.0f));
    n = gaussian_blur_masked(n, Image(), 3.0f);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            set_normal(n, x, y, Vec3f(n.at(x, y, 0), n.at(x, y, 1), n.at(x, y, 2)));
    return n;
}

/// L1 distance between the tilt histograms (relief_statistics.h): a rotation-invariant
/// statistic of the relief, independent of the patch search.
double tilt_histogram_distance(const Image& a, const Image& b) {
    return histogram_l1_distance(tilt_histogram(a), tilt_histogram(b));
}

GuidanceRequest tactile_request(const Image& normals, const Image& mask, std::uint64_t seed = 5) {
    GuidanceRequest r;
    r.kind = GuidanceKind::Tactile;
    r.strength = 0.8;
    r.seed = seed;
    r.images = {normals};
    r.masks = {mask};
    return r;
}

ExemplarPatchMatchBackend::Options small_options() {
    ExemplarPatchMatchBackend::Options o;
    o.patch_size = 5;
    o.levels = 2;
    o.search_iterations = 4;
    o.em_iterations = 2;
    return o;
}

TEST(GuidanceExemplarPatchMatch, RotatedExemplarContentIsFoundExactly) {
    const Image exemplar = bump_exemplar(48);
    const Image target = crop(rotate90(exemplar), 5, 9, 24, 24);
    const Image mask(24, 24, 1, 1.0f);

    ExemplarPatchMatchBackend::Options upright = small_options();
    upright.rotations = 1;
    upright.flip_rows = false;
    ExemplarPatchMatchBackend without_rotations(upright);
    without_rotations.set_exemplars({exemplar});

    ExemplarPatchMatchBackend with_rotations(small_options());
    with_rotations.set_exemplars({exemplar});

    // 90-degree variants are exact, so the rotated content has distance 0 (up to float rounding).
    EXPECT_LT(with_rotations.mean_nearest_patch_distance(target, mask), 1e-8);
    EXPECT_GT(without_rotations.mean_nearest_patch_distance(target, mask), 1e-2);

    // Refining content that exists in the exemplar returns it (PatchMatch finds the exact match).
    // One level: coarser levels of an odd-offset crop do not exist in the exemplar's pyramid.
    ExemplarPatchMatchBackend::Options one_level = small_options();
    one_level.levels = 1;
    ExemplarPatchMatchBackend fine_only(one_level);
    fine_only.set_exemplars({exemplar});
    const Image refined = fine_only.refine(tactile_request(target, mask)).refined[0];
    double max_error = 0.0;
    for (std::size_t i = 0; i < target.values().size(); ++i)
        max_error = std::max(max_error, double(std::abs(refined.values()[i] - target.values()[i])));
    EXPECT_LT(max_error, 1e-3) << "max error " << max_error;
}

TEST(GuidanceExemplarPatchMatch, ExemplarStatisticsMoveTowardTheExemplar) {
    const Image exemplar = bump_exemplar(48);
    ExemplarPatchMatchBackend backend(small_options());
    backend.set_exemplars({exemplar});

    const int size = 32;
    Image mask(size, size, 1, 1.0f);
    Image normals = smooth_normals(size, 3);
    const double nn_before = backend.mean_nearest_patch_distance(normals, mask);
    const double tilt_before = tilt_histogram_distance(normals, exemplar);

    // The optimizer's effect, abstracted: each guidance iteration moves the normals half way to the
    // target and renormalizes. Without guidance they stay as they are (statistics unchanged).
    for (int i = 0; i < 6; ++i) {
        const Image target =
            backend.refine(tactile_request(normals, mask, 100 + std::uint64_t(i))).refined[0];
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const float* t = target.pixel(x, y);
                const float* n = normals.pixel(x, y);
                set_normal(normals,
                           x,
                           y,
                           Vec3f(n[0] + 0.5f * (t[0] - n[0]),
                                 n[1] + 0.5f * (t[1] - n[1]),
                                 n[2] + 0.5f * (t[2] - n[2])));
            }
    }
    const double nn_after = backend.mean_nearest_patch_distance(normals, mask);
    const double tilt_after = tilt_histogram_distance(normals, exemplar);
    std::printf(
        "nearest-patch distance %.4f -> %.4f, tilt histogram L1 %.3f -> %.3f (no guidance: unchanged)\n",
        nn_before,
        nn_after,
        tilt_before,
        tilt_after);
    EXPECT_LT(nn_after, 0.25 * nn_before);
    EXPECT_LT(tilt_after, 0.5 * tilt_before);
}

TEST(GuidanceExemplarPatchMatch, BackgroundIsKeptAndCoverageScalesTheNormals) {
    ExemplarPatchMatchBackend backend(small_options());
    backend.set_exemplars({bump_exemplar(48)});
    const int size = 24;
    Image normals = smooth_normals(size, 4);
    Image mask(size, size, 1, 1.0f);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < 6; ++x) {
            mask.at(x, y, 0) = 0.0f;
            set_normal(normals, x, y, Vec3f(0.0f, 0.0f, 1.0f));
            normals.at(x, y, 2) = 0.0f;  // background: zero vectors, as the renders have
        }
    for (int y = 0; y < size; ++y) mask.at(6, y, 0) = 0.5f;  // antialiased silhouette column
    const Image refined = backend.refine(tactile_request(normals, mask)).refined[0];
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < 6; ++x)
            for (int c = 0; c < 3; ++c) ASSERT_EQ(refined.at(x, y, c), normals.at(x, y, c));
        const float* edge = refined.pixel(6, y);
        EXPECT_NEAR(length(Vec3f(edge[0], edge[1], edge[2])), 0.5f, 1e-4f);
        const float* inside = refined.pixel(12, y);
        EXPECT_NEAR(length(Vec3f(inside[0], inside[1], inside[2])), 1.0f, 1e-4f);
    }
}

TEST(GuidanceExemplarPatchMatch, DeterministicForSeedAndThreadCount) {
    // Through the base interface, as a trainer would do it.
    const auto created = GuidanceBackend::create(
        "exemplar_patch_match", Json{{"patch_size", 5}, {"levels", 2}, {"search_iterations", 4}});
    GuidanceBackend& backend = *created;
    backend.set_exemplars({bump_exemplar(40)});
    const Image normals = smooth_normals(40, 6);
    const Image mask(40, 40, 1, 1.0f);
    const GuidanceRequest request = tactile_request(normals, mask, 9);
    const Image many = backend.refine(request).refined[0];
    Image one;
    {
        ThreadLimit limit(1);
        one = backend.refine(request).refined[0];
    }
    EXPECT_EQ(many.values(), one.values());
    const Image other_seed = backend.refine(tactile_request(normals, mask, 10)).refined[0];
    EXPECT_NE(many.values(), other_seed.values());
}

TEST(GuidanceExemplarPatchMatch, ConfigAndRequestErrors) {
    using Options = ExemplarPatchMatchBackend::Options;
    EXPECT_THROW(Options::from_json(Json{{"patch_size", 4}}), Error);
    EXPECT_THROW(Options::from_json(Json{{"rotations", 3}}), Error);
    EXPECT_THROW(Options::from_json(Json{{"exemplars", "a.png"}}), Error);
    EXPECT_THROW(Options::from_json(Json{{"levls", 2}}), Error);
    EXPECT_THROW(
        Options::from_json(Json{{"exemplars", Json::array({"/nonexistent/x.png"})}}).exemplar_files.at(1),
        std::out_of_range);
    EXPECT_THROW(GuidanceBackend::create("exemplar_patch_match",
                                         Json{{"exemplars", Json::array({"/nonexistent/x.png"})}}),
                 Error);

    ExemplarPatchMatchBackend backend(small_options());
    const Image normals = smooth_normals(16, 1);
    const Image mask(16, 16, 1, 1.0f);
    EXPECT_THROW(backend.refine(tactile_request(normals, mask)), Error);  // no exemplars yet
    EXPECT_THROW(backend.set_exemplars({Image(3, 3, 3, 0.0f)}), Error);   // smaller than a patch
    backend.set_exemplars({bump_exemplar(24)});
    GuidanceRequest visual = tactile_request(normals, mask);
    visual.kind = GuidanceKind::Visual;
    EXPECT_THROW(backend.refine(visual), Error);
}

TEST(GuidanceExemplarPatchMatch, RealTactileSamplePullsSmoothNormalsTowardIt) {
    TDF_REQUIRE_SHARED_DATA("tactile/texture_samples/avocado_00000.png");
    const Image sample =
        load_tactile_map(test::shared_data_dir() + "/tactile/texture_samples/avocado_00000.png").normals;
    ASSERT_EQ(sample.width(), 240);
    // Exemplar: the top-left 96x96 of the capture. Target: a disjoint 32x32 region, rotated by
    // 90 degrees and blurred (a smooth field that only knows the coarse relief).
    const Image exemplar = crop(sample, 0, 0, 96, 96);
    Image target = gaussian_blur_masked(rotate90(crop(sample, 150, 150, 32, 32)), Image(), 2.0f);
    const Image mask(32, 32, 1, 1.0f);
    ExemplarPatchMatchBackend::Options options = small_options();
    ExemplarPatchMatchBackend backend(options);
    backend.set_exemplars({exemplar});
    const double before = backend.mean_nearest_patch_distance(target, mask);
    for (int i = 0; i < 4; ++i) {
        const Image refined = backend.refine(tactile_request(target, mask, std::uint64_t(i))).refined[0];
        for (std::size_t k = 0; k < target.values().size(); ++k)
            target.values()[k] += 0.5f * (refined.values()[k] - target.values()[k]);
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; ++x)
                set_normal(target, x, y, Vec3f(target.at(x, y, 0), target.at(x, y, 1), target.at(x, y, 2)));
    }
    const double after = backend.mean_nearest_patch_distance(target, mask);
    std::printf("avocado: nearest exemplar patch distance %.5f -> %.5f\n", before, after);
    EXPECT_LT(after, 0.5 * before);
}

}  // namespace
}  // namespace tdf


namespace tdf {
namespace {

/// Rodrigues rotation of v about the unit `axis` by `angle`.
Vec3f rotate_about(Vec3f v, Vec3f axis, float angle) {
    return v * std::cos(angle) + cross(axis, v) * std::sin(angle) + axis * (dot(axis, v) * (1.0f - std::cos(angle)));
}

/// A tactile request showing `detail` (tangent-space normals, u to the right) laid on a
/// sphere cap seen from above: every normal and the tangent are tilted with the cap's surface
/// normal, as the optimizer's patch renders are. Returns the request with its surface frames.
GuidanceRequest curved_request(const Image& detail, float handedness) {
    const int size = detail.width();
    Image normals(size, size, 3), base(size, size, 3), tangents(size, size, 4);
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const float c = 0.5f * float(size - 1);
            const Vec3f a = safe_normalize(Vec3f((float(x) - c) / 30.0f, (c - float(y)) / 30.0f, 1.0f));
            const Vec3f axis = safe_normalize(cross(Vec3f(0, 0, 1), a));
            const float angle = std::acos(std::clamp(a.z, -1.0f, 1.0f));
            const float* d = detail.pixel(x, y);
            set_normal(normals, x, y, rotate_about(Vec3f(d[0], d[1], d[2]), axis, angle));
            set_normal(base, x, y, a);
            const Vec3f t = rotate_about(Vec3f(1, 0, 0), axis, angle);
            float* tp = tangents.pixel(x, y);
            tp[0] = t.x, tp[1] = t.y, tp[2] = t.z, tp[3] = handedness;
        }
    GuidanceRequest r = tactile_request(normals, Image(size, size, 1, 1.0f));
    r.surface_normals = {base};
    r.surface_tangents = {tangents};
    return r;
}

double max_abs_difference(const Image& a, const Image& b) {
    double e = 0.0;
    for (std::size_t i = 0; i < a.values().size(); ++i) e = std::max(e, double(std::abs(a.values()[i] - b.values()[i])));
    return e;
}

/// Rows reversed and y negated: the map as a chart of handedness -1 shows it.
Image mirrored(const Image& image) {
    Image out(image.width(), image.height(), 3);
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x) {
            const float* s = image.pixel(x, image.height() - 1 - y);
            set_normal(out, x, y, Vec3f(s[0], -s[1], s[2]));
        }
    return out;
}

ExemplarPatchMatchBackend::Options exact_options() {
    ExemplarPatchMatchBackend::Options o = small_options();
    o.levels = 1;
    o.search_iterations = 8;
    o.match_tilt_histogram = false;  // a crop's histogram is not the whole exemplar's
    return o;
}

}  // namespace

TEST(GuidanceExemplarPatchMatch, SurfaceFramesSeparateTheReliefFromTheCurvature) {
    const Image exemplar = bump_exemplar(48);
    const Image detail = crop(exemplar, 7, 3, 24, 24);
    ExemplarPatchMatchBackend backend(exact_options());
    backend.set_exemplars({exemplar});

    // With the frames the relief under the curvature is exemplar content: found exactly.
    const GuidanceRequest request = curved_request(detail, 1.0f);
    const double with_frames = max_abs_difference(backend.refine(request).refined[0], request.images[0]);
    EXPECT_LT(with_frames, 2e-3);

    // Without them the cap's tilt (up to 21 degrees) is taken for texture and replaced.
    GuidanceRequest bare = request;
    bare.surface_normals.clear();
    bare.surface_tangents.clear();
    const double without_frames = max_abs_difference(backend.refine(bare).refined[0], request.images[0]);
    EXPECT_GT(without_frames, 0.1);
    std::printf("curved exemplar crop: max error %.5f with surface frames, %.3f without\n", with_frames, without_frames);
}

TEST(GuidanceExemplarPatchMatch, SurfaceFramesGiveTheMapsTurnAndMirroring) {
    // The bumps and the vertical ridge look the same mirrored; a diagonal ridge does not.
    Image exemplar = bump_exemplar(48);
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x)
            if ((x + y) % 16 < 3) set_normal(exemplar, x, y, Vec3f(0.6f, 0.6f, 1.0f));
    ExemplarPatchMatchBackend backend(exact_options());
    backend.set_exemplars({exemplar});

    // A chart of handedness -1 shows the map mirrored; the frames say so, so it is found.
    const GuidanceRequest request = curved_request(crop(mirrored(exemplar), 11, 5, 24, 24), -1.0f);
    EXPECT_LT(max_abs_difference(backend.refine(request).refined[0], request.images[0]), 2e-3);
    // Claiming handedness +1 for the same image makes it foreign content.
    GuidanceRequest wrong = request;
    for (std::size_t p = 0; p < wrong.surface_tangents[0].pixel_count(); ++p) wrong.surface_tangents[0].data()[4 * p + 3] = 1.0f;
    EXPECT_GT(max_abs_difference(backend.refine(wrong).refined[0], request.images[0]), 0.05);
}

TEST(GuidanceExemplarPatchMatch, MagnifiedPatchesAreSearchedAsACoarserCopy) {
    // The map magnified 8x, as the optimizer's patches see it: one texel spans 8 pixels.
    const Image exemplar = bump_exemplar(48);
    const Image magnified = resize_bilinear(crop(exemplar, 4, 4, 12, 12), 96, 96);
    const Image mask(96, 96, 1, 1.0f);
    ExemplarPatchMatchBackend::Options options = small_options();
    options.levels = 1;
    ExemplarPatchMatchBackend backend(options);
    backend.set_exemplars({exemplar});

    GuidanceRequest request = tactile_request(magnified, mask);
    request.pixels_per_texel = 8.0f;
    const Image refined = backend.refine(request).refined[0];
    // Searched at the right scale the content is the exemplar's: the change stays small.
    double mean_change = 0.0;
    for (std::size_t i = 0; i < refined.values().size(); ++i) mean_change += std::abs(refined.values()[i] - magnified.values()[i]);
    mean_change /= double(refined.values().size());
    // At scale 1 the smooth magnified ramps match nothing in the exemplar and are rebuilt.
    request.pixels_per_texel = 1.0f;
    const Image unscaled = backend.refine(request).refined[0];
    double mean_change_unscaled = 0.0;
    for (std::size_t i = 0; i < unscaled.values().size(); ++i)
        mean_change_unscaled += std::abs(unscaled.values()[i] - magnified.values()[i]);
    mean_change_unscaled /= double(unscaled.values().size());
    std::printf("8x magnified crop: mean change %.4f at pixels_per_texel 8, %.4f at 1\n", mean_change, mean_change_unscaled);
    EXPECT_LT(mean_change, 0.5 * mean_change_unscaled);
}

TEST(GuidanceExemplarPatchMatch, ScaleAndOrientationOptions) {
    using Options = ExemplarPatchMatchBackend::Options;
    EXPECT_EQ(Options::from_json(Json::object()).exemplar_scale, 0.0f);  // auto
    EXPECT_EQ(Options::from_json(Json{{"exemplar_scale", "auto"}}).exemplar_scale, 0.0f);
    EXPECT_EQ(Options::from_json(Json{{"exemplar_scale", 2}}).exemplar_scale, 2.0f);
    EXPECT_THROW(Options::from_json(Json{{"exemplar_scale", "big"}}), Error);
    EXPECT_THROW(Options::from_json(Json{{"exemplar_scale", 0}}), Error);
    EXPECT_EQ(Options::from_json(Json{{"orientation", "search"}}).orientation, Options::Orientation::Search);
    EXPECT_THROW(Options::from_json(Json{{"orientation", "up"}}), Error);

    // Frames must come one of each per image, of the image's size.
    ExemplarPatchMatchBackend backend(small_options());
    backend.set_exemplars({bump_exemplar(24)});
    GuidanceRequest request = curved_request(crop(bump_exemplar(24), 0, 0, 16, 16), 1.0f);
    request.surface_tangents.clear();
    EXPECT_THROW(backend.refine(request), Error);
    request = curved_request(crop(bump_exemplar(24), 0, 0, 16, 16), 1.0f);
    request.surface_tangents[0] = Image(16, 16, 3);
    EXPECT_THROW(backend.refine(request), Error);
    request = curved_request(crop(bump_exemplar(24), 0, 0, 16, 16), 1.0f);
    request.pixels_per_texel = -1.0f;
    EXPECT_THROW(backend.refine(request), Error);
}

}  // namespace tdf
