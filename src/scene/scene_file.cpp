#include <tdf/scene/scene_file.h>

#include <tdf/core/error.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

namespace tdf {

namespace fs = std::filesystem;

const std::vector<std::string>& foreign_scene_sections() {
    static const std::vector<std::string> names = {"optimize", "tactile_layout", "guidance", "export", "field", "schedule"};
    return names;
}

namespace {

std::string resolve_path(const fs::path& base, const std::string& relative) {
    if (relative.empty()) return relative;
    const fs::path p(relative);
    return (p.is_absolute() ? p : base / p).lexically_normal().string();
}

Vec3f read_vec3(ConfigReader& reader, const std::string& key, Vec3f fallback) {
    if (!reader.has(key)) {
        reader.get<int>(key, 0);  // marks it read
        return fallback;
    }
    const Json& v = reader.raw(key);
    if (v.is_number()) return Vec3f{v.get<float>(), v.get<float>(), v.get<float>()};
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
        throw_error("{}: '{}' must be a number or an array of 3 numbers, got {}", reader.where(), key, v.dump());
    const Vec3f out{v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    if (!is_finite(out)) throw_error("{}: '{}' must be finite", reader.where(), key);
    return out;
}

float finite(ConfigReader& reader, const std::string& key, float fallback) {
    const float v = reader.get<float>(key, fallback);
    if (!std::isfinite(v)) throw_error("{}: '{}' must be a finite number", reader.where(), key);
    return v;
}

float positive(ConfigReader& reader, const std::string& key, float fallback) {
    const float v = finite(reader, key, fallback);
    if (!(v > 0.f)) throw_error("{}: '{}' must be positive, got {}", reader.where(), key, v);
    return v;
}

int non_negative(ConfigReader& reader, const std::string& key, int fallback) {
    const int v = reader.get<int>(key, fallback);
    if (v < 0) throw_error("{}: '{}' must not be negative, got {}", reader.where(), key, v);
    return v;
}

std::string one_of(ConfigReader& reader, const std::string& key, const std::string& fallback,
                   const std::vector<std::string>& valid) {
    const std::string v = reader.get<std::string>(key, fallback);
    if (std::find(valid.begin(), valid.end(), v) == valid.end()) {
        std::string list;
        for (const auto& s : valid) list += (list.empty() ? "" : ", ") + s;
        throw_error("{}: '{}' is '{}' (valid: {})", reader.where(), key, v, list);
    }
    return v;
}

std::vector<std::string> string_list(ConfigReader& reader, const std::string& key,
                                     const std::vector<std::string>& fallback) {
    if (!reader.has(key)) {
        reader.get<int>(key, 0);
        return fallback;
    }
    const Json& v = reader.raw(key);
    if (v.is_string()) return {v.get<std::string>()};
    std::vector<std::string> out;
    if (!v.is_array()) throw_error("{}: '{}' must be a string or a list of strings", reader.where(), key);
    for (const Json& item : v) {
        if (!item.is_string()) throw_error("{}: '{}' must contain only strings, got {}", reader.where(), key, item.dump());
        out.push_back(item.get<std::string>());
    }
    return out;
}

void parse_views(ConfigReader views, ViewsSpec& spec) {
    spec.radius = positive(views, "radius", spec.radius);
    spec.fovy = positive(views, "fovy", spec.fovy);
    if (spec.fovy >= 180.f) throw_error("{}: 'fovy' must be below 180 degrees, got {}", views.where(), spec.fovy);
    spec.target = read_vec3(views, "target", spec.target);
    if (views.has("orbit")) {
        const Json& list = views.raw("orbit");
        if (!list.is_array()) throw_error("{}: 'orbit' must be a list of views", views.where());
        for (std::size_t k = 0; k < list.size(); ++k) {
            ConfigReader view(list[k], fmt::format("{}.orbit[{}]", views.where(), k));
            OrbitViewSpec o;
            o.elevation = finite(view, "elevation", 0.f);
            o.azimuth = finite(view, "azimuth", 0.f);
            o.radius = positive(view, "radius", spec.radius);
            o.fovy = positive(view, "fovy", spec.fovy);
            view.check_all_read();
            spec.orbit.push_back(o);
        }
    } else {
        views.get<int>("orbit", 0);
    }
    ConfigReader turntable = views.child("turntable");
    spec.turntable_count = non_negative(turntable, "count", 0);
    spec.turntable_elevation = finite(turntable, "elevation", 0.f);
    turntable.check_all_read();
    ConfigReader random = views.child("random");
    spec.random_count = non_negative(random, "count", 0);
    spec.random_ssaa = random.get<bool>("ssaa", false);
    random.check_all_read();
    ConfigReader patches = views.child("patches");
    spec.patch_count = non_negative(patches, "count", 0);
    spec.patch_reference_flip = patches.get<bool>("reference_flip", false);
    patches.check_all_read();
    views.check_all_read();
    const long long total =
        (long long)spec.orbit.size() + spec.turntable_count + spec.random_count + spec.patch_count;
    if (total > kMaxSceneViews)
        throw_error("{}: {} views in all (orbit + turntable + random + patches) is over the limit of {}",
                    views.where(),
                    total,
                    kMaxSceneViews);
    if (spec.orbit.empty() && spec.turntable_count == 0 && spec.random_count == 0 && spec.patch_count == 0)
        spec.orbit.push_back({0.f, 0.f, spec.radius, spec.fovy});
}

void parse_light(ConfigReader light, const std::string& shading, LightSpec& spec) {
    spec.mode = one_of(light, "mode", spec.mode, {"camera", "directional", "point", "magic3d"});
    spec.relative_elevation = finite(light, "relative_elevation", 0.f);
    spec.relative_azimuth = finite(light, "relative_azimuth", 0.f);
    spec.elevation = finite(light, "elevation", 0.f);
    spec.azimuth = finite(light, "azimuth", 0.f);
    spec.position = read_vec3(light, "position", spec.position);
    // Training shade 0.5 max(0, n.l) + 0.5 (spec 3.4); visualizer ambient ratio 0.1 (spec 3.9).
    spec.ambient = finite(light, "ambient", shading == "training" ? 0.5f : 0.1f);
    if (spec.ambient < 0.f || spec.ambient > 1.f)
        throw_error("{}: 'ambient' must be in [0, 1], got {}", light.where(), spec.ambient);
    light.check_all_read();
}

std::string select_value(const Json& item, const std::string& where) {
    if (item.is_string()) return item.get<std::string>();
    if (item.is_number_integer()) return std::to_string(item.get<long long>());
    throw_error("{}: 'select' must contain strings or integers, got {}", where, item.dump());
}

void parse_parts(ConfigReader parts, const fs::path& base, PartsSpec& spec) {
    ConfigReader source = parts.child("source");
    PartsSourceSpec& src = spec.source;
    src.kind = one_of(source, "kind", src.kind, {"mesh", "label_image", "face_labels", "colour", "external"});
    src.key = one_of(source, "key", src.key, {"material", "object", "group", "primitive"});
    src.image = resolve_path(base, source.get<std::string>("image", ""));
    src.file = resolve_path(base, source.get<std::string>("file", ""));
    src.k = source.get<int>("k", src.k);
    src.k_max = source.get<int>("k_max", src.k_max);
    src.smoothing = source.get<int>("smoothing", src.smoothing);
    if (source.has("external"))
        src.external = source.raw("external");
    else
        source.get<int>("external", 0);
    source.check_all_read();
    const std::string where = source.where();
    if (src.kind == "label_image" && src.image.empty())
        throw_error("{}: kind is 'label_image' but 'image' is not set", where);
    if (src.kind == "face_labels" && src.file.empty())
        throw_error("{}: kind is 'face_labels' but 'file' is not set", where);
    if (src.k == 1 || src.k < 0 || src.k > 16)
        throw_error("{}: 'k' must be 0 (choose) or in [2, 16], got {}", where, src.k);
    if (src.k_max < 2 || src.k_max > 16)
        throw_error("{}: 'k_max' must be in [2, 16], got {}", where, src.k_max);
    if (src.smoothing < 0 || src.smoothing > 50)
        throw_error("{}: 'smoothing' must be in [0, 50], got {}", where, src.smoothing);
    if (src.kind == "external" && (!src.external.is_object() || !src.external.contains("command")))
        throw_error("{}: kind is 'external' but 'external.command' is not set", where);

    if (!parts.has("list")) throw_error("{}: 'list' is missing (at least 1 part)", parts.where());
    const Json& list = parts.raw("list");
    if (!list.is_array()) throw_error("{}: 'list' must be a list of parts", parts.where());
    if (list.empty()) throw_error("{}: 'list' is empty; at least 1 part is needed", parts.where());
    if (list.size() > 64)
        throw_error("{}: 'list' has {} parts; at most 64 are supported", parts.where(), list.size());
    int without_select = 0;
    for (std::size_t k = 0; k < list.size(); ++k) {
        ConfigReader item(list[k], fmt::format("{}.list[{}]", parts.where(), k));
        PartSpec p;
        p.name = item.require<std::string>("name");
        if (p.name.empty() ||
            p.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
                std::string::npos)
            throw_error("{}: 'name' is '{}'; use letters, digits, '_' and '-'", item.where(), p.name);
        for (const PartSpec& other : spec.parts)
            if (other.name == p.name)
                throw_error("{}: 'name' '{}' is used by two parts", item.where(), p.name);
        ConfigReader tactile = item.child("tactile");
        for (const auto& image : string_list(tactile, "images", {}))
            p.tactile_images.push_back(resolve_path(base, image));
        tactile.check_all_read();
        if (p.tactile_images.empty())
            throw_error("{}: 'tactile.images' is empty (each part needs a tactile map)", item.where());
        ConfigReader layout = item.child("layout");
        p.layout.mode = one_of(layout, "mode", p.layout.mode, {"atlas", "physical"});
        p.layout.repeat = positive(layout, "repeat", 1.f);
        p.layout.mm_per_unit = finite(layout, "mm_per_unit", 0.f);
        p.layout.mm_per_pixel = finite(layout, "mm_per_pixel", 0.f);
        layout.check_all_read();
        if (p.layout.mode == "physical" && !(p.layout.mm_per_unit > 0))
            throw_error("{}: layout.mode is 'physical' but 'layout.mm_per_unit' is not a positive number",
                        item.where());
        p.prompt = item.get<std::string>("prompt", "");
        if (item.has("guidance")) {
            p.guidance = item.raw("guidance");
            if (!p.guidance.is_object()) throw_error("{}: 'guidance' must be an object", item.where());
        } else {
            item.get<int>("guidance", 0);
        }
        if (item.has("select")) {
            const Json& sel = item.raw("select");
            if (sel.is_array()) {
                for (const Json& s : sel) p.select.push_back(select_value(s, item.where()));
            } else {
                p.select.push_back(select_value(sel, item.where()));
            }
            if (p.select.empty()) throw_error("{}: 'select' is an empty list", item.where());
        } else {
            item.get<int>("select", 0);
            ++without_select;
        }
        item.check_all_read();
        spec.parts.push_back(std::move(p));
    }
    if (without_select > 1 && without_select < int(spec.parts.size()))
        throw_error(
            "{}: {} parts have no 'select'; at most one part may take the regions no other part selects",
            parts.where(),
            without_select);
    for (std::size_t a = 0; a < spec.parts.size(); ++a)
        for (std::size_t b = a + 1; b < spec.parts.size(); ++b)
            for (const std::string& s : spec.parts[a].select)
                if (std::find(spec.parts[b].select.begin(), spec.parts[b].select.end(), s) !=
                    spec.parts[b].select.end())
                    throw_error("{}: '{}' is selected by both '{}' and '{}'",
                                parts.where(),
                                s,
                                spec.parts[a].name,
                                spec.parts[b].name);
    if (src.k >= 2 && without_select == int(spec.parts.size()) && src.k != int(spec.parts.size()))
        throw_error(
            "{}: 'k' is {} but there are {} parts and none has a 'select' (set k to {} or select clusters)",
            source.where(),
            src.k,
            spec.parts.size(),
            spec.parts.size());
    parts.check_all_read();
}

}  // namespace

SceneDescription parse_scene(const Json& json, const std::string& path) {
    const fs::path base = fs::path(path).parent_path();
    ConfigReader root(json, path);
    SceneDescription s;
    s.path = path;
    s.mesh = resolve_path(base, root.require<std::string>("mesh"));
    s.normalize = root.get<bool>("normalize", false);
    s.normalize_bound = positive(root, "normalize_bound", 0.9f);
    const std::string tangents = one_of(root, "tangents", "handed", {"handed", "reference"});
    s.tangents = tangents == "handed" ? TangentMode::Handed : TangentMode::Reference;

    s.object_name = root.get<std::string>("object_name", "");
    ConfigReader uv = root.child("uv");
    s.uv_reunwrap = uv.get<bool>("reunwrap", false);
    uv.check_all_read();

    ConfigReader albedo = root.child("albedo");
    s.albedo_source = one_of(albedo, "source", "mesh", {"mesh", "image", "vertex_colors", "constant"});
    s.albedo_image = resolve_path(base, albedo.get<std::string>("image", ""));
    s.albedo_color = read_vec3(albedo, "color", s.albedo_color);
    albedo.check_all_read();
    if (s.albedo_source == "image" && s.albedo_image.empty())
        throw_error("{}: albedo.source is 'image' but albedo.image is not set", path);

    ConfigReader tactile = root.child("tactile");
    for (const auto& image : string_list(tactile, "images", {})) s.tactile_images.push_back(resolve_path(base, image));
    tactile.check_all_read();
    s.label_map = resolve_path(base, root.get<std::string>("label_map", ""));

    ConfigReader image = root.child("image");
    s.width = image.get<int>("width", 512);
    s.height = image.get<int>("height", 512);
    if (s.width <= 0 || s.height <= 0 || s.width > 16384 || s.height > 16384)
        throw_error("{}: image size {}x{} is invalid (each side must be in 1..16384)", image.where(), s.width,
                    s.height);
    image.check_all_read();
    s.ssaa = finite(root, "ssaa", 1.f);
    if (s.ssaa < 1.f || s.ssaa > 4.f) throw_error("{}: 'ssaa' must be in [1, 4], got {}", path, s.ssaa);
    s.shading = one_of(root, "shading", s.shading, {"training", "visualizer"});
    s.renderer = one_of(root, "renderer", s.renderer, {"ray", "raster"});
    s.antialias = root.get<bool>("antialias", s.renderer == "raster");
    s.background = read_vec3(root, "background", s.background);
    s.color_space = one_of(root, "color_space", s.color_space, {"raw", "srgb"});
    s.passes = string_list(root, "passes", s.passes);
    if (s.passes.empty()) throw_error("{}: 'passes' is empty", path);
    s.seed = root.get<std::uint64_t>("seed", 0);
    parse_views(root.child("views"), s.views);
    // Supersampled views render at `ssaa` times the size (random views at up to 2x).
    const float largest_ssaa = std::max(s.ssaa, s.views.random_count > 0 && s.views.random_ssaa ? 2.f : 1.f);
    if (float(std::max(s.width, s.height)) * largest_ssaa > float(kMaxRenderSide))
        throw_error(
            "{}: image {}x{} at ssaa {} renders {:.0f} pixels wide, over the limit of {} (lower 'ssaa' or "
            "'image.width'/'image.height')",
            path,
            s.width,
            s.height,
            largest_ssaa,
            float(std::max(s.width, s.height)) * largest_ssaa,
            kMaxRenderSide);
    parse_light(root.child("light"), s.shading, s.light);
    if (root.has("parts")) {
        if (!root.raw("parts").is_object())
            throw_error("{}: 'parts' must be an object with 'source' and 'list'", path);
        parse_parts(root.child("parts"), base, s.parts);
    } else {
        root.get<int>("parts", 0);
    }
    for (const auto& name : foreign_scene_sections())
        if (root.has(name)) s.sections[name] = root.raw(name);
    root.check_all_read();
    return s;
}

SceneDescription load_scene(const std::string& path, const std::vector<std::string>& overrides) {
    if (!fs::exists(path)) throw_error("cannot open scene '{}': no such file", path);
    Json json = load_json_file(path);
    for (const auto& o : overrides) {
        try {
            apply_override(json, o);
        } catch (const Error& e) {
            throw_error("{}: {}", path, e.what());
        }
    }
    return parse_scene(json, path);
}

Json SceneDescription::to_json() const {
    auto vec = [](Vec3f v) { return Json::array({v.x, v.y, v.z}); };
    // Absolute, so the resolved file still works from the output folder.
    auto absolute = [](const std::string& p) { return p.empty() ? p : fs::absolute(p).lexically_normal().string(); };
    std::vector<std::string> tactile;
    for (const auto& t : tactile_images) tactile.push_back(absolute(t));
    Json orbit = Json::array();
    for (const auto& o : views.orbit)
        orbit.push_back({{"elevation", o.elevation}, {"azimuth", o.azimuth}, {"radius", o.radius}, {"fovy", o.fovy}});
    Json j = {
        {"mesh", absolute(mesh)},
        {"normalize", normalize},
        {"normalize_bound", normalize_bound},
        {"tangents", tangents == TangentMode::Handed ? "handed" : "reference"},
        {"object_name", object_name},
        {"uv", {{"reunwrap", uv_reunwrap}}},
        {"albedo", {{"source", albedo_source}, {"image", absolute(albedo_image)}, {"color", vec(albedo_color)}}},
        {"tactile", {{"images", tactile}}},
        {"label_map", absolute(label_map)},
        {"image", {{"width", width}, {"height", height}}},
        {"ssaa", ssaa},
        {"shading", shading},
        {"renderer", renderer},
        {"antialias", antialias},
        {"background", vec(background)},
        {"color_space", color_space},
        {"passes", passes},
        {"seed", seed},
        {"views",
         {{"radius", views.radius},
          {"fovy", views.fovy},
          {"target", vec(views.target)},
          {"orbit", orbit},
          {"turntable", {{"count", views.turntable_count}, {"elevation", views.turntable_elevation}}},
          {"random", {{"count", views.random_count}, {"ssaa", views.random_ssaa}}},
          {"patches", {{"count", views.patch_count}, {"reference_flip", views.patch_reference_flip}}}}},
        {"light",
         {{"mode", light.mode},
          {"relative_elevation", light.relative_elevation},
          {"relative_azimuth", light.relative_azimuth},
          {"elevation", light.elevation},
          {"azimuth", light.azimuth},
          {"position", vec(light.position)},
          {"ambient", light.ambient}}},
    };
    if (parts.enabled()) {
        Json list = Json::array();
        for (const PartSpec& p : parts.parts) {
            std::vector<std::string> images;
            for (const auto& t : p.tactile_images) images.push_back(absolute(t));
            Json item = {{"name", p.name},
                         {"tactile", {{"images", images}}},
                         {"layout",
                          {{"mode", p.layout.mode},
                           {"repeat", p.layout.repeat},
                           {"mm_per_unit", p.layout.mm_per_unit},
                           {"mm_per_pixel", p.layout.mm_per_pixel}}},
                         {"prompt", p.prompt},
                         {"guidance", p.guidance}};
            if (!p.select.empty()) item["select"] = p.select;  // absent = takes the rest
            list.push_back(item);
        }
        const PartsSourceSpec& src = parts.source;
        j["parts"] = {{"source",
                       {{"kind", src.kind},
                        {"key", src.key},
                        {"image", absolute(src.image)},
                        {"file", absolute(src.file)},
                        {"k", src.k},
                        {"k_max", src.k_max},
                        {"smoothing", src.smoothing},
                        {"external", src.external}}},
                      {"list", list}};
    }
    for (const auto& [name, section] : sections) j[name] = section;
    return j;
}

}  // namespace tdf
