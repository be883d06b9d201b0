#include <tdf/core/error.h>
#include <tdf/core/parallel.h>
#include <tdf/core/rng.h>
#include <tdf/core/vec.h>
#include <tdf/guidance/exemplar_patch_match.h>
#include <tdf/tactile/tactile_map.h>
#include <tdf/guidance/image_filters.h>

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

/// L1 distance between the histograms (16 bins over [0, 60] degrees) of the normals' tilt from
/// +z: a rotation-invariant statistic of the relief, independent of the patch search.
double tilt_histogram_distance(const Image& a, const Image& b) {
    const auto histogram = [](const Image& image) {
        std::vector<double> h(16, 0.0);
        for (std::size_t p = 0; p < image.pixel_count(); ++p) {
            const float z = std::clamp(image.data()[3 * p + 2], -1.0f, 1.0f);
            const int bin = std::min(15, int(degrees(std::acos(z)) / 60.0f * 16.0f));
            h[std::size_t(bin)] += 1.0 / double(image.pixel_count());
        }
        return h;
    };
    const auto ha = histogram(a), hb = histogram(b);
    double d = 0.0;
    for (std::size_t i = 0; i < ha.size(); ++i) d += std::abs(ha[i] - hb[i]);
    return d;
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
