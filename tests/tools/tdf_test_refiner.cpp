// tdf_test_refiner: a PROTOCOL TEST PROGRAM for the "external" guidance backend, not a model.
// It reads request.json as docs/guidance-protocol.md specifies and writes every output with a
// fixed, deterministic transform, so tests can check the plumbing end to end:
//   visual:  refined = 1 - input (colour inverted), RGB PNG;
//   tactile: refined normal = (-x, -y, z) of the input (rotated by 180 degrees in the image
//            plane), written as EXR (--format exr, default) or as a (n + 1) / 2 PNG (--format png).
// Failure modes on request: --exit N (print to stderr, exit N), --hang (wait forever, for
// timeouts), --skip-output K (do not write output K), --wrong-size (outputs one pixel wider),
// --gray (write 1-channel outputs).
//
// Usage: tdf_test_refiner [options] <request.json>
#include <tdf/core/atomic_file.h>
#include <tdf/core/config.h>
#include <tdf/core/error.h>
#include <tdf/io/image_io.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

struct Settings {
    std::string request;
    int exit_code = 0;
    bool hang = false;
    int skip_output = -1;
    bool wrong_size = false;
    bool gray = false;
    bool exr = true;
};

int fail(const std::string& message) {
    std::fprintf(stderr, "tdf_test_refiner: %s\n", message.c_str());
    return 2;
}

tdf::Image transform(const tdf::Image& input, bool visual) {
    tdf::Image out = input;
    float* p = out.data();
    for (std::size_t i = 0; i < out.pixel_count(); ++i, p += 3) {
        if (visual) {
            for (int c = 0; c < 3; ++c) p[c] = 1.0f - p[c];
        } else {
            p[0] = -p[0];
            p[1] = -p[1];
        }
    }
    return out;
}

tdf::Image resized_output(const tdf::Image& image, const Settings& settings) {
    const int width = image.width() + (settings.wrong_size ? 1 : 0);
    const int channels = settings.gray ? 1 : 3;
    tdf::Image out(width, image.height(), channels);
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c)
                out.at(x, y, c) = image.at(std::min(x, image.width() - 1), y, c);
    return out;
}

int run(const Settings& settings) {
    const tdf::Json request = tdf::load_json_file(settings.request);
    if (request.value("protocol", "") != "tdf-guidance/1")
        return fail(settings.request + ": protocol is not tdf-guidance/1");
    const std::string kind = request.at("kind").get<std::string>();
    const bool visual = kind == "visual";
    if (!visual && kind != "tactile") return fail(settings.request + ": unknown kind " + kind);
    const int width = request.at("width").get<int>();
    const int height = request.at("height").get<int>();
    const std::string folder = request.at("folder").get<std::string>();
    const auto& images = request.at("images");
    if (images.size() != request.at("count").get<std::size_t>()) return fail("count does not match images");
    for (std::size_t k = 0; k < images.size(); ++k) {
        const auto& entry = images[k];
        // Visual inputs are colours; tactile inputs are read from the raw EXR.
        const std::string input_file =
            folder + "/" + entry.at(visual ? "input" : "input_exr").get<std::string>();
        tdf::Image input = tdf::read_image(input_file);
        if (input.width() != width || input.height() != height || input.channels() < 3)
            return fail(input_file + ": unexpected size or channels");
        if (input.channels() > 3) input = input.channel_range(0, 3);
        const tdf::Image mask = tdf::read_image(folder + "/" + entry.at("mask").get<std::string>());
        if (mask.width() != width || mask.height() != height) return fail("mask size mismatch");
        if (visual) {
            const tdf::Image control = tdf::read_image(folder + "/" + entry.at("control").get<std::string>());
            if (control.width() != width || control.channels() != 3) return fail("control image mismatch");
        }
        if (int(k) == settings.skip_output) continue;
        const tdf::Image refined = resized_output(transform(input, visual), settings);
        if (visual) {
            tdf::write_png(
                folder + "/" + entry.at("output").get<std::string>(), refined, 8, tdf::Quantize::Round);
        } else if (settings.exr) {
            tdf::write_exr(folder + "/" + entry.at("output_exr").get<std::string>(), refined);
        } else {
            tdf::Image encoded = refined;
            for (float& v : encoded.values()) v = (v + 1.0f) * 0.5f;
            tdf::write_png(
                folder + "/" + entry.at("output").get<std::string>(), encoded, 16, tdf::Quantize::Round);
        }
    }
    std::printf("tdf_test_refiner: wrote %zu %s output(s)\n", images.size(), kind.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    Settings settings;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const bool has_value = i + 1 < argc;
        if (arg == "--exit" && has_value) {
            settings.exit_code = std::atoi(argv[++i]);
        } else if (arg == "--hang") {
            settings.hang = true;
        } else if (arg == "--skip-output" && has_value) {
            settings.skip_output = std::atoi(argv[++i]);
        } else if (arg == "--wrong-size") {
            settings.wrong_size = true;
        } else if (arg == "--gray") {
            settings.gray = true;
        } else if (arg == "--format" && has_value) {
            settings.exr = std::string(argv[++i]) == "exr";
        } else if (!arg.empty() && arg[0] != '-') {
            settings.request = arg;
        } else {
            return fail("unknown option " + arg);
        }
    }
    if (settings.exit_code != 0) {
        std::fprintf(stderr, "tdf_test_refiner: failing on purpose\nwith exit code %d\n", settings.exit_code);
        return settings.exit_code;
    }
    if (settings.hang)
        while (true) pause();  // until the caller's timeout kills the process group
    if (settings.request.empty()) return fail("usage: tdf_test_refiner [options] <request.json>");
    try {
        return run(settings);
    } catch (const std::exception& e) {
        return fail(e.what());
    }
}
