#include <tdf/batch/grid.h>
#include <tdf/core/error.h>

#include <filesystem>
#include <set>

namespace tdf {

namespace fs = std::filesystem;

namespace {

std::string clean_name(const std::string& text) {
    std::string out;
    for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' ? c : '_';
    while (!out.empty() && out.front() == '.') out.erase(0, 1);
    return out.empty() ? "job" : out.substr(0, 80);
}

std::string existing_absolute(const std::string& path, const char* what) {
    if (!fs::exists(path)) throw_error("tdf batch grid: {} '{}' does not exist", what, path);
    return fs::absolute(path).lexically_normal().string();
}

}  // namespace

std::vector<BatchJob> make_grid(const GridSpec& spec) {
    if (spec.command != "optimize" && spec.command != "render")
        throw_error("tdf batch grid: --command must be optimize or render, not '{}'", spec.command);
    if (spec.scenes.empty()) throw_error("tdf batch grid: give at least one scene or mesh (--scene)");
    const std::vector<std::string> textures =
        spec.textures.empty() ? std::vector<std::string>{""} : spec.textures;
    const std::vector<std::string> sets =
        spec.override_sets.empty() ? std::vector<std::string>{""} : spec.override_sets;
    std::vector<BatchJob> jobs;
    std::set<std::string> names;
    for (const std::string& item : spec.scenes) {
        const std::string path = existing_absolute(item, "scene or mesh");
        const bool is_scene = fs::path(path).extension() == ".json";
        std::vector<std::string> head;
        std::string object;
        if (is_scene) {
            head = {path};
            object = fs::path(path).parent_path().filename().string();
        } else {
            if (spec.base_scene.empty())
                throw_error(
                    "tdf batch grid: '{}' is a mesh: give --base-scene, the scene file it is placed in",
                    item);
            head = {existing_absolute(spec.base_scene, "base scene"), "mesh=" + path};
            object = fs::path(path).stem().string();
        }
        for (const std::string& texture : textures) {
            std::vector<std::string> with_texture = head;
            std::string name = object;
            if (!texture.empty()) {
                with_texture.push_back("tactile.images=[\"" + existing_absolute(texture, "texture") + "\"]");
                name += "_" + fs::path(texture).stem().string();
            }
            for (std::size_t k = 0; k < sets.size(); ++k) {
                BatchJob job;
                job.command = spec.command;
                job.args = with_texture;
                for (const std::string& o : split_arguments(sets[k], "--overrides")) job.args.push_back(o);
                std::string unique = clean_name(sets.size() > 1 ? name + "_" + std::to_string(k) : name);
                for (int n = 2; names.count(unique); ++n) unique = clean_name(name) + "_" + std::to_string(n);
                names.insert(unique);
                job.name = unique;
                jobs.push_back(job);
            }
        }
    }
    return jobs;
}

}  // namespace tdf
