// The `external` parts source (protocol in docs/parts-protocol.md). One call for all views: the
// program may batch them (a segmenter loads its weights once).
#include <tdf/parts/external_segmentation.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/guidance/subprocess.h>
#include <tdf/io/image_io.h>
#include <tdf/parts/colour_segmentation.h>
#include <tdf/parts/part_segmentation.h>
#include <tdf/render/trace.h>
#include <tdf/scene/camera.h>
#include <tdf/scene/embree_scene.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace tdf {

namespace fs = std::filesystem;

namespace {

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
        text.replace(at, from.size(), to);
    return text;
}

// The `external` source's settings (docs/parts-protocol.md "Configuration"), checked.
struct ExternalCall {
    std::vector<std::string> argv;
    bool shell = false;
    double timeout = 600.0;
    int views = 8, resolution = 512;
    float radius = 3.f, fovy = 50.f;
    std::vector<float> elevations;
    bool keep_files = false;
};

ExternalCall read_external_call(const Json& config, const std::string& where) {
    ExternalCall call;
    ConfigReader reader(config, where);
    if (!reader.has("command")) throw_error("{}: 'command' is required", where);
    const Json& command = reader.raw("command");
    const bool shell = call.shell = reader.get<bool>("shell", false);
    std::vector<std::string>& argv = call.argv;
    if (command.is_string()) {
        if (shell) {
            argv = {command.get<std::string>()};
        } else {
            std::istringstream words(command.get<std::string>());
            for (std::string w; words >> w;) argv.push_back(w);
        }
    } else if (command.is_array() && !shell) {
        for (const Json& a : command) {
            if (!a.is_string()) throw_error("{}: 'command' must be an array of strings", where);
            argv.push_back(a.get<std::string>());
        }
    } else {
        throw_error("{}: 'command' must be a string, or an array of strings without 'shell'", where);
    }
    if (argv.empty() || argv[0].empty()) throw_error("{}: 'command' is empty", where);
    const double timeout = call.timeout = reader.get<double>("timeout_seconds", 600.0);
    const int views = call.views = reader.get<int>("views", 8);
    const int resolution = call.resolution = reader.get<int>("resolution", 512);
    call.radius = reader.get<float>("radius", 3.f);
    call.fovy = reader.get<float>("fovy", 50.f);
    call.elevations = reader.get<std::vector<float>>("elevations", {-20.f, 20.f});
    call.keep_files = reader.get<bool>("keep_files", false);
    reader.check_all_read();
    if (!(timeout > 0)) throw_error("{}: 'timeout_seconds' must be positive", where);
    if (views < 1 || views > 256) throw_error("{}: 'views' must be in [1, 256], got {}", where, views);
    if (resolution < 16 || resolution > 4096)
        throw_error("{}: 'resolution' must be in [16, 4096], got {}", where, resolution);
    if (call.elevations.empty()) throw_error("{}: 'elevations' is empty", where);

    return call;
}

// Votes per face and part: every pixel a view sees, in the part whose mask is strongest there
// (> 0.5), read from the program's part_<view>_<part>.png.
std::vector<float> read_votes(const std::vector<GBuffer>& buffers, std::size_t face_count, std::size_t part_count,
                              int resolution, const std::string& folder, const std::string& where) {
    const int views = int(buffers.size());
    std::vector<float> votes(face_count * part_count, 0.f);
    for (int k = 0; k < views; ++k) {
        const GBuffer& g = buffers[std::size_t(k)];
        std::vector<Image> masks;
        for (std::size_t p = 0; p < part_count; ++p) {
            const std::string file = fmt::format("{}/part_{}_{}.png", folder, k, p);
            if (!fs::exists(file))
                throw_error("{}: the program did not write {} (files kept in {})", where, file, folder);
            Image m = read_image(file);
            if (m.width() != resolution || m.height() != resolution)
                throw_error("{}: {} is {}x{}, expected {}x{}",
                            where,
                            file,
                            m.width(),
                            m.height(),
                            resolution,
                            resolution);
            masks.push_back(std::move(m));
        }
        for (int y = 0; y < resolution; ++y)
            for (int x = 0; x < resolution; ++x) {
                const std::size_t i = g.index(x, y);
                if (g.triangle[i] < 0) continue;
                int best = -1;
                float best_v = 0.5f;
                for (std::size_t p = 0; p < part_count; ++p) {
                    const float v = masks[p].at(x, y, 0);
                    if (!std::isfinite(v))
                        throw_error("{}: part_{}_{}.png has a non-finite value", where, k, p);
                    if (v > best_v) {
                        best_v = v;
                        best = int(p);
                    }
                }
                if (best >= 0) votes[std::size_t(g.triangle[i]) * part_count + std::size_t(best)] += 1.f;
            }
    }
    return votes;
}

// Unseen faces (label -1) take their neighbours' part, repeatedly; any still unlabelled get part 0.
void fill_unseen_faces(std::vector<int>& label, const std::vector<std::vector<std::pair<int, float>>>& adjacency,
                       std::size_t part_count) {
    for (bool changed = true; changed;) {
        changed = false;
        std::vector<int> next(label);
        for (std::size_t f = 0; f < label.size(); ++f) {
            if (label[f] >= 0) continue;
            std::vector<float> v(part_count, 0.f);
            for (const auto& [g, w] : adjacency[f])
                if (label[std::size_t(g)] >= 0) v[std::size_t(label[std::size_t(g)])] += w;
            const auto best = std::max_element(v.begin(), v.end());
            if (*best > 0) {
                next[f] = int(best - v.begin());
                changed = true;
            }
        }
        label.swap(next);
    }
    for (int& l : label)
        if (l < 0) l = 0;
}

}  // namespace

std::vector<int> run_external_segmentation(const Json& config, const ExternalSegmentationInput& input) {
    const std::string& where = input.where;
    if (!input.mesh || !input.material) throw_error("{}: no mesh", where);
    const ExternalCall call = read_external_call(config, where);
    std::vector<std::string> argv = call.argv;
    const bool shell = call.shell;
    const double timeout = call.timeout;
    const int views = call.views, resolution = call.resolution;
    const float radius = call.radius, fovy = call.fovy;
    const std::vector<float>& elevations = call.elevations;
    const std::string parent =
        input.work_folder.empty() ? fs::temp_directory_path().string() : input.work_folder;
    const std::string folder =
        fs::absolute(fs::path(parent) / fmt::format("tdf-parts-{}", ::getpid())).string();
    fs::remove_all(folder);
    ensure_folder(folder);

    const TriangleMesh& mesh = *input.mesh;
    const EmbreeScene scene(mesh);
    std::vector<GBuffer> buffers;
    Json images = Json::array();
    for (int k = 0; k < views; ++k) {
        const float azimuth = 360.f * float(k) / float(views);
        const float elevation = elevations[std::size_t(k) % elevations.size()];
        const Camera camera = Camera::orbit(elevation, azimuth, radius, fovy, resolution, resolution);
        GBuffer g = trace_gbuffer(scene, mesh, camera);
        Image colour(resolution, resolution, 3, 1.f), mask(resolution, resolution, 1, 0.f);
        for (int y = 0; y < resolution; ++y)
            for (int x = 0; x < resolution; ++x) {
                const std::size_t i = g.index(x, y);
                if (g.triangle[i] < 0) continue;
                const Vec2f b = g.barycentric[i];
                const Vec3f a = albedo_at(mesh, *input.material, g.triangle[i], {1.f - b.x - b.y, b.x, b.y});
                // Headlight shading keeps the shape readable for the segmenter.
                const float shade = 0.35f + 0.65f * std::fabs(dot(g.normal[i], camera.back));
                for (int c = 0; c < 3; ++c) colour.at(x, y, c) = std::clamp(a[c] * shade, 0.f, 1.f);
                mask.at(x, y, 0) = 1.f;
            }
        write_png(fmt::format("{}/input_{}.png", folder, k), colour);
        write_png(fmt::format("{}/mask_{}.png", folder, k), mask);
        Json outputs = Json::array();
        for (std::size_t p = 0; p < input.part_names.size(); ++p)
            outputs.push_back(fmt::format("part_{}_{}.png", k, p));
        images.push_back({{"input", fmt::format("input_{}.png", k)},
                          {"mask", fmt::format("mask_{}.png", k)},
                          {"outputs", outputs},
                          {"elevation", elevation},
                          {"azimuth", azimuth}});
        buffers.push_back(std::move(g));
    }
    Json parts = Json::array();
    for (std::size_t p = 0; p < input.part_names.size(); ++p) {
        const std::string prompt =
            p < input.prompts.size() && !input.prompts[p].empty() ? input.prompts[p] : input.part_names[p];
        parts.push_back({{"index", p}, {"name", input.part_names[p]}, {"prompt", prompt}});
    }
    const std::string request = folder + "/request.json";
    write_text_atomically(request,
                          Json{{"protocol", "tdf-parts/1"},
                               {"width", resolution},
                               {"height", resolution},
                               {"count", views},
                               {"folder", folder},
                               {"parts", parts},
                               {"images", images}}
                                  .dump(2) +
                              "\n");
    bool placed = false;
    for (std::string& a : argv) {
        if (a.find("{request}") != std::string::npos || a.find("{folder}") != std::string::npos)
            placed = true;
        a = replace_all(replace_all(a, "{request}", request), "{folder}", folder);
    }
    if (!placed) {
        if (shell)
            argv[0] += " " + request;
        else
            argv.push_back(request);
    }
    if (shell) argv = {"/bin/sh", "-c", argv[0]};
    const ProcessOutcome outcome =
        run_process(argv, folder, timeout, folder + "/stdout.txt", folder + "/stderr.txt");
    if (outcome.timed_out)
        throw_error(
            "{}: '{}' timed out after {} s (files kept in {})", where, format_command(argv), timeout, folder);
    if (outcome.exit_code != 0)
        throw_error("{}: '{}' failed (exit {}, signal {}): {} (files kept in {})",
                    where,
                    format_command(argv),
                    outcome.exit_code,
                    outcome.signal,
                    file_tail(folder + "/stderr.txt", 1),
                    folder);

    const std::size_t part_count = input.part_names.size();
    const std::vector<float> votes = read_votes(buffers, mesh.triangles.size(), part_count, resolution, folder, where);
    std::vector<int> label(mesh.triangles.size(), -1);
    std::size_t seen = 0;
    for (std::size_t f = 0; f < label.size(); ++f) {
        const float* v = &votes[f * part_count];
        const auto best = std::max_element(v, v + part_count);
        if (*best > 0) {
            label[f] = int(best - v);
            ++seen;
        }
    }
    if (seen == 0) throw_error("{}: the masks cover no visible face (files kept in {})", where, folder);
    const auto adjacency = face_adjacency(mesh);
    // Unseen faces take their neighbours' part, then a few rounds of majority smoothing.
    fill_unseen_faces(label, adjacency, part_count);
    majority_smooth(label, adjacency, input.smoothing);
    log_info("{}: {} of {} faces seen in {} views ({:.1f} s in the program)",
             where,
             seen,
             label.size(),
             views,
             outcome.seconds);
    if (!call.keep_files) fs::remove_all(folder);
    return label;
}

}  // namespace tdf
