#include <tdf/guidance/external_backend.h>

#include <tdf/core/atomic_file.h>
#include <tdf/core/error.h>
#include <tdf/core/log.h>
#include <tdf/guidance/schedule.h>
#include <tdf/guidance/subprocess.h>
#include <tdf/io/image_io.h>

#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>

namespace tdf {

namespace fs = std::filesystem;

namespace {
constexpr const char* kProtocol = "tdf-guidance/1";

std::vector<std::string> split_spaces(const std::string& text) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (start < text.size()) {
        const auto end = text.find(' ', start);
        const std::string part = text.substr(start, end == std::string::npos ? end : end - start);
        if (!part.empty()) parts.push_back(part);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return parts;
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
        text.replace(at, from.size(), to);
    return text;
}

bool has_placeholder(const std::string& text) {
    return text.find("{request}") != std::string::npos || text.find("{folder}") != std::string::npos;
}

Image normals_to_unit_range(const Image& normals) {
    Image out = normals;
    for (float& v : out.values()) v = (v + 1.0f) * 0.5f;
    return out;
}

std::string one_line(std::string text) {
    for (char& c : text)
        if (c == '\n' || c == '\r') c = '|';
    return text;
}
}  // namespace

ExternalBackend::Options ExternalBackend::Options::from_json(const Json& config) {
    ConfigReader reader(config, "guidance backend 'external'");
    Options o;
    if (!reader.has("command"))
        throw_error("{}: \"command\" is required (the program to run per guidance call)", reader.where());
    const Json& command = reader.raw("command");
    o.shell = reader.get<bool>("shell", o.shell);
    if (command.is_string()) {
        const std::string text = command.get<std::string>();
        o.command = o.shell ? std::vector<std::string>{text} : split_spaces(text);
    } else if (command.is_array()) {
        if (o.shell)
            throw_error("{}: \"shell\": true needs \"command\" as one string, not an array", reader.where());
        for (const Json& arg : command) {
            if (!arg.is_string()) throw_error("{}: \"command\" must be an array of strings", reader.where());
            o.command.push_back(arg.get<std::string>());
        }
    } else {
        throw_error("{}: \"command\" must be a string or an array of strings", reader.where());
    }
    if (o.command.empty() || o.command[0].empty()) throw_error("{}: \"command\" is empty", reader.where());
    o.timeout_seconds = reader.get<double>("timeout_seconds", o.timeout_seconds);
    if (!(o.timeout_seconds > 0.0))
        throw_error("{}: timeout_seconds {} must be positive", reader.where(), o.timeout_seconds);
    o.work_folder = reader.get<std::string>("work_folder", o.work_folder);
    o.keep_files = reader.get<bool>("keep_files", o.keep_files);
    if (reader.has("kinds")) {
        const Json& kinds = reader.raw("kinds");
        if (!kinds.is_array() || kinds.empty())
            throw_error("{}: \"kinds\" must be a non-empty array of \"visual\" / \"tactile\"",
                        reader.where());
        o.kinds.clear();
        for (const Json& kind : kinds) {
            if (!kind.is_string())
                throw_error("{}: \"kinds\" must be an array of \"visual\" / \"tactile\"", reader.where());
            o.kinds.push_back(parse_guidance_kind(kind.get<std::string>(), reader.where() + ": kinds"));
        }
    }
    reader.check_all_read();
    return o;
}

ExternalBackend::ExternalBackend(Options options) : m_options(std::move(options)) {
    TDF_CHECK(!m_options.command.empty());
    m_temporary_work_folder = m_options.work_folder.empty();
    m_work_folder = m_temporary_work_folder
                        ? (fs::temp_directory_path() / fmt::format("tdf-guidance-{}", getpid())).string()
                        : m_options.work_folder;
    m_work_folder = fs::absolute(m_work_folder).lexically_normal().string();
}

ExternalBackend::~ExternalBackend() {
    std::error_code ignored;
    if (m_temporary_work_folder && fs::is_empty(m_work_folder, ignored)) fs::remove(m_work_folder, ignored);
}

bool ExternalBackend::supports(GuidanceKind kind) const {
    for (GuidanceKind k : m_options.kinds)
        if (k == kind) return true;
    return false;
}

Json write_guidance_request(const std::string& folder, const GuidanceRequest& request) {
    validate_request(request, folder);
    ensure_folder(folder);
    const bool visual = request.kind == GuidanceKind::Visual;
    Json json;
    json["protocol"] = kProtocol;
    json["kind"] = guidance_kind_name(request.kind);
    json["prompt"] = request.prompt;
    json["negative_prompt"] = request.negative_prompt;
    json["strength"] = request.strength;
    json["ddim_steps"] = kGuidanceDdimSteps;
    json["start_index"] = ddim_start_index(request.strength);
    json["start_timestep"] = ddim_start_timestep(request.strength);
    json["denoise_fraction"] = denoise_fraction(request.strength);
    json["iteration"] = request.iteration;
    json["seed"] = request.seed;
    if (!visual) json["pixels_per_texel"] = request.pixels_per_texel;
    json["width"] = request.images[0].width();
    json["height"] = request.images[0].height();
    json["count"] = request.images.size();
    json["folder"] = folder;
    json["encodings"] = {
        {"input",
         visual ? "8-bit RGB PNG, colour in [0,1] on white" : "8-bit RGB PNG, (n+1)/2 of view-space normals"},
        {"input_exr", "float EXR R,G,B = view-space normal x (right), y (up), z (toward viewer)"},
        {"control", "8-bit RGB PNG, normal-BAE ControlNet control image (red = left, green = up)"},
        {"mask", "8-bit gray PNG, coverage in [0,1], 0 = background"},
        {"output", visual ? "PNG RGB (or RGBA), colour in [0,1]" : "PNG RGB, (n+1)/2 of refined normals"},
        {"output_exr", "float EXR R,G,B refined normals in [-1,1] (used instead of output when present)"},
    };
    Json images = Json::array();
    Json outputs = Json::array();
    for (std::size_t k = 0; k < request.images.size(); ++k) {
        Json entry;
        entry["index"] = k;
        entry["input"] = fmt::format("input_{}.png", k);
        entry["mask"] = fmt::format("mask_{}.png", k);
        entry["output"] = fmt::format("refined_{}.png", k);
        const std::string dir = folder + "/";
        write_png(dir + entry["mask"].get<std::string>(), request.masks[k], 8, Quantize::Round);
        if (visual) {
            entry["control"] = fmt::format("control_{}.png", k);
            write_png(dir + entry["input"].get<std::string>(), request.images[k], 8, Quantize::Round);
            write_png(dir + entry["control"].get<std::string>(), request.control[k], 8, Quantize::Round);
        } else {
            entry["input_exr"] = fmt::format("input_{}.exr", k);
            entry["output_exr"] = fmt::format("refined_{}.exr", k);
            write_png(dir + entry["input"].get<std::string>(),
                      normals_to_unit_range(request.images[k]),
                      8,
                      Quantize::Round);
            write_exr(dir + entry["input_exr"].get<std::string>(), request.images[k]);
        }
        outputs.push_back(entry["output"]);
        images.push_back(std::move(entry));
    }
    json["images"] = std::move(images);
    json["outputs"] = std::move(outputs);
    write_text_atomically(folder + "/request.json", json.dump(2) + "\n");
    return json;
}

GuidanceResult read_guidance_outputs(const std::string& folder, const Json& request_json,
                                     const GuidanceRequest& request, const std::string& command) {
    const bool visual = request.kind == GuidanceKind::Visual;
    GuidanceResult result;
    const Json& images = request_json.at("images");
    TDF_CHECK_EQ(images.size(), request.images.size());
    for (std::size_t k = 0; k < images.size(); ++k) {
        const Image& input = request.images[k];
        std::string path = folder + "/" + images[k].at("output").get<std::string>();
        bool raw_normals = false;
        if (!visual) {
            const std::string exr = folder + "/" + images[k].at("output_exr").get<std::string>();
            if (fs::exists(exr)) {
                path = exr;
                raw_normals = true;
            }
        }
        if (!fs::exists(path)) throw_error("guidance command '{}' did not write '{}'", command, path);
        Image image;
        try {
            image = read_image(path);
        } catch (const Error& e) {
            throw_error("guidance command '{}' wrote an unreadable output: {}", command, e.what());
        }
        if (image.width() != input.width() || image.height() != input.height())
            throw_error("guidance command '{}' wrote '{}' of size {}x{}, expected {}x{}",
                        command,
                        path,
                        image.width(),
                        image.height(),
                        input.width(),
                        input.height());
        if (image.channels() < 3)
            throw_error("guidance command '{}' wrote '{}' with {} channel(s), expected RGB",
                        command,
                        path,
                        image.channels());
        if (image.channels() > 3) image = image.channel_range(0, 3);
        if (!image.all_finite())
            throw_error("guidance command '{}' wrote '{}' with non-finite values", command, path);
        const Image& mask = request.masks[k];
        for (std::size_t p = 0; p < image.pixel_count(); ++p) {
            float* v = image.data() + 3 * p;
            if (visual) {
                // Matches reference: refined background forced to white (spec 5.4).
                if (mask.data()[p] == 0.0f) v[0] = v[1] = v[2] = 1.0f;
            } else if (!raw_normals) {
                // Matches reference: refined normals mapped back with x * 2 - 1 (spec 5.5).
                for (int c = 0; c < 3; ++c) v[c] = v[c] * 2.0f - 1.0f;
            }
        }
        result.refined.push_back(std::move(image));
    }
    return result;
}

GuidanceResult ExternalBackend::refine(const GuidanceRequest& request) {
    if (!supports(request.kind))
        throw_error("guidance backend 'external' is not configured for {} requests (see \"kinds\")",
                    guidance_kind_name(request.kind));
    const std::string folder = fmt::format(
        "{}/{}_{:05d}_{:04d}", m_work_folder, guidance_kind_name(request.kind), request.iteration, m_calls++);
    m_last_call_folder = folder;
    std::error_code ec;
    fs::remove_all(folder, ec);  // a stale folder from an earlier run with the same pid
    const Json request_json = write_guidance_request(folder, request);

    const std::string request_path = folder + "/request.json";
    std::vector<std::string> argv;
    if (m_options.shell) {
        std::string script = replace_all(m_options.command[0], "{request}", request_path);
        script = replace_all(script, "{folder}", folder);
        argv = {"/bin/sh", "-c", script};
    } else {
        bool placeholder = false;
        for (const std::string& arg : m_options.command) {
            placeholder = placeholder || has_placeholder(arg);
            argv.push_back(replace_all(replace_all(arg, "{request}", request_path), "{folder}", folder));
        }
        if (!placeholder) argv.push_back(request_path);
    }
    const std::string command = format_command(argv);
    const std::string stderr_path = folder + "/stderr.txt";
    log_verbose("guidance: running {} ({} {} image(s), iteration {})",
                command,
                request.images.size(),
                guidance_kind_name(request.kind),
                request.iteration);

    ProcessOutcome outcome;
    try {
        outcome = run_process(argv, folder, m_options.timeout_seconds, folder + "/stdout.txt", stderr_path);
    } catch (const Error& e) {
        throw_error("guidance backend 'external': {} (call folder kept: {})", e.what(), folder);
    }
    if (outcome.timed_out)
        throw_error("guidance command '{}' timed out after {} s and was killed (call folder kept: {})",
                    command,
                    m_options.timeout_seconds,
                    folder);
    if (outcome.signal != 0 || outcome.exit_code != 0) {
        const std::string ended = outcome.signal != 0
                                      ? fmt::format("was killed by signal {}", outcome.signal)
                                      : fmt::format("exited with status {}", outcome.exit_code);
        throw_error("guidance command '{}' {} (call folder kept: {}); stderr: {}",
                    command,
                    ended,
                    folder,
                    one_line(file_tail(stderr_path)));
    }

    GuidanceResult result = read_guidance_outputs(folder, request_json, request, command);
    log_verbose("guidance: {} finished in {:.2f} s", command, outcome.seconds);
    if (!m_options.keep_files) fs::remove_all(folder, ec);
    return result;
}

}  // namespace tdf
