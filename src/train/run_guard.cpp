#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <tdf/core/atomic_file.h>
#include <tdf/core/hash.h>
#include <tdf/core/log.h>
#include <tdf/core/parallel.h>
#include <tdf/optim/checkpoint.h>
#include <tdf/scene/scene_file.h>
#include <tdf/train/run_guard.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace tdf {

namespace fs = std::filesystem;

// ---- output names -------------------------------------------------------------------------

void validate_output_target(const std::string& output_dir, const std::string& name) {
    if (output_dir.empty())
        throw_error("-o/--output is empty: give an output folder (use '.' for the current folder)");
    if (name.empty() || name == "." || name == ".." || name.find_first_of("/\\") != std::string::npos)
        throw_error(
            "--name '{}' is not a plain file name prefix: it must be non-empty, not '.' or '..', and contain "
            "no '/' (files must stay inside the output folder)",
            name);
}

// ---- stop signals -------------------------------------------------------------------------

namespace {

volatile sig_atomic_t g_stop_signal = 0;
struct sigaction g_previous[3];
constexpr int kStopSignals[3] = {SIGTERM, SIGINT, SIGUSR1};

void write_stderr(const char* text) {
    ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
    (void)ignored;
}

extern "C" void on_stop_signal(int signal) {
    if (g_stop_signal != 0) {
        if (signal == SIGINT) {
            // Ctrl-C twice: the user does not want to wait for the iteration to end.
            ::signal(SIGINT, SIG_DFL);
            raise(SIGINT);
        }
        return;
    }
    g_stop_signal = signal;
    // Only async-signal-safe calls here: fixed texts through write(2).
    write_stderr(signal == SIGTERM
                     ? "tdf: SIGTERM received: stopping at the next iteration boundary with a checkpoint\n"
                 : signal == SIGINT
                     ? "tdf: SIGINT received: stopping at the next iteration boundary with a checkpoint "
                       "(Ctrl-C again to kill)\n"
                     : "tdf: SIGUSR1 received: stopping at the next iteration boundary with a checkpoint\n");
}

}  // namespace

StopSignals::StopSignals() {
    struct sigaction action {};
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;
    for (int k = 0; k < 3; ++k) sigaction(kStopSignals[k], &action, &g_previous[k]);
}

StopSignals::~StopSignals() {
    for (int k = 0; k < 3; ++k) sigaction(kStopSignals[k], &g_previous[k], nullptr);
}

bool stop_requested() { return g_stop_signal != 0; }
int stop_signal() { return int(g_stop_signal); }
void clear_stop_request() { g_stop_signal = 0; }

std::string signal_name(int signal) {
    switch (signal) {
        case SIGTERM:
            return "SIGTERM";
        case SIGINT:
            return "SIGINT";
        case SIGUSR1:
            return "SIGUSR1";
        case SIGKILL:
            return "SIGKILL";
        default:
            return fmt::format("signal {}", signal);
    }
}

void throw_interrupted(int iteration, const std::string& checkpoint_path) {
    throw RunInterrupted(
        fmt::format("interrupted by {} after iteration {}: checkpoint written to '{}'; continue with "
                    "--resume (exit code {})",
                    signal_name(stop_signal()),
                    iteration,
                    checkpoint_path,
                    kExitInterrupted));
}

// ---- output folder lock -------------------------------------------------------------------

OutputFolderLock::OutputFolderLock(const std::string& folder, const std::string& command) {
    ensure_folder(folder);
    const std::string path = (fs::path(folder) / kLockFileName).string();
    // Never truncate on open: the current holder's description must survive a refused attempt.
    m_fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (m_fd < 0) throw_error("cannot create lock file '{}': {}", path, std::strerror(errno));
    if (flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
        const int error = errno;
        close(m_fd);
        m_fd = -1;
        if (error != EWOULDBLOCK)
            throw_error("cannot lock output folder '{}': {}", folder, std::strerror(error));
        std::string holder = read_text_file(path);
        while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\r')) holder.pop_back();
        throw_error("output folder '{}' is in use by another tdf run ({}); wait for it or choose another -o",
                    folder,
                    holder.empty() ? "holder unknown" : holder);
    }
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    const std::string holder = fmt::format("{} on {}, pid {}\n", command, host, getpid());
    if (ftruncate(m_fd, 0) == 0) {
        ssize_t ignored = pwrite(m_fd, holder.data(), holder.size(), 0);
        (void)ignored;
    }
}

OutputFolderLock::~OutputFolderLock() {
    // The file stays: deleting it would let a waiting process lock an unlinked inode while a
    // third one locks a new file.
    if (m_fd >= 0) {
        flock(m_fd, LOCK_UN);
        close(m_fd);
    }
}

// ---- temporaries --------------------------------------------------------------------------

bool is_atomic_temporary(const std::string& file_name) {
    // write_atomically(): stem + ".tmp" + pid + "_" + counter + extension.
    static const std::regex pattern(R"(.*\.tmp[0-9]+_[0-9]+(\.[^.]*)?)");
    return std::regex_match(file_name, pattern);
}

std::vector<std::string> remove_stale_temporaries(const std::string& folder) {
    std::vector<std::string> removed;
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) return removed;
    for (auto it = fs::recursive_directory_iterator(folder, ec);
         !ec && it != fs::recursive_directory_iterator();
         it.increment(ec)) {
        if (!it->is_regular_file(ec) || !is_atomic_temporary(it->path().filename().string())) continue;
        std::error_code remove_error;
        if (fs::remove(it->path(), remove_error)) removed.push_back(it->path().string());
    }
    std::sort(removed.begin(), removed.end());
    return removed;
}

// ---- input hashes -------------------------------------------------------------------------

namespace {

// The files an OBJ reads besides itself: its MTL libraries and their maps.
void obj_sidecars(const fs::path& obj, std::set<std::string>& out) {
    std::ifstream in(obj);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("mtllib", 0) != 0) continue;
        std::istringstream words(line.substr(6));
        std::string mtl;
        while (words >> mtl) {
            const fs::path mtl_path = obj.parent_path() / mtl;
            if (!fs::exists(mtl_path)) continue;
            out.insert(mtl_path.string());
            std::ifstream mtl_in(mtl_path);
            std::string mtl_line;
            while (std::getline(mtl_in, mtl_line)) {
                std::istringstream tokens(mtl_line);
                std::string key, last, token;
                tokens >> key;
                if (key.rfind("map_", 0) != 0 && key != "norm" && key != "bump") continue;
                while (tokens >> token) last = token;  // options such as "-bm 1" precede the file
                const fs::path map = mtl_path.parent_path() / last;
                if (!last.empty() && fs::exists(map)) out.insert(map.string());
            }
        }
    }
}

// glTF (not .glb) external buffers and images.
void gltf_sidecars(const fs::path& gltf, std::set<std::string>& out) {
    Json json;
    try {
        json = load_json_file(gltf.string());
    } catch (const Error&) {
        return;  // the loader reports a bad file itself
    }
    for (const char* key : {"buffers", "images"}) {
        if (!json.contains(key) || !json[key].is_array()) continue;
        for (const Json& item : json[key])
            if (item.contains("uri") && item["uri"].is_string()) {
                const std::string uri = item["uri"].get<std::string>();
                if (uri.rfind("data:", 0) != 0) out.insert((gltf.parent_path() / uri).string());
            }
    }
}

}  // namespace

std::vector<std::string> scene_input_files(const SceneDescription& scene,
                                           const std::vector<std::string>& extra) {
    std::set<std::string> files(extra.begin(), extra.end());
    // The scene file and its parents (a parent may change what the scene means).
    fs::path scene_file = scene.path;
    for (int depth = 0; depth < 32 && !scene_file.empty() && fs::exists(scene_file); ++depth) {
        if (!files.insert(scene_file.string()).second) break;  // a cycle; load_scene reports it
        Json json;
        try {
            json = load_json_file(scene_file.string());
        } catch (const Error&) {
            break;
        }
        if (!json.contains("parent") || !json["parent"].is_string()) break;
        scene_file = scene_file.parent_path() / json["parent"].get<std::string>();
    }
    if (!scene.mesh.empty()) {
        files.insert(scene.mesh);
        const std::string ext = fs::path(scene.mesh).extension().string();
        if (ext == ".obj" || ext == ".OBJ") obj_sidecars(scene.mesh, files);
        if (ext == ".gltf") gltf_sidecars(scene.mesh, files);
    }
    if (!scene.albedo_image.empty()) files.insert(scene.albedo_image);
    for (const std::string& t : scene.tactile_images) files.insert(t);
    if (!scene.label_map.empty()) files.insert(scene.label_map);
    return {files.begin(), files.end()};
}

std::vector<std::string> guidance_exemplar_files(const Json& guidance_config) {
    std::vector<std::string> files;
    if (!guidance_config.is_object()) return files;
    for (auto it = guidance_config.begin(); it != guidance_config.end(); ++it)
        if (it->is_object() && it->contains("exemplars") && (*it)["exemplars"].is_array())
            for (const Json& file : (*it)["exemplars"])
                if (file.is_string()) files.push_back(file.get<std::string>());
    return files;
}

Json hash_input_files(const std::vector<std::string>& paths) {
    Json out = Json::object();
    for (const std::string& path : paths) out[path] = hash_hex(hash_file(path));
    return out;
}

std::string describe_input_changes(const Json& recorded, const Json& current) {
    std::vector<std::string> changes;
    for (auto it = recorded.begin(); it != recorded.end(); ++it) {
        const auto now = current.find(it.key());
        if (now == current.end())
            changes.push_back(it.key() + " is no longer an input");
        else if (*now != *it)
            changes.push_back(it.key() + " changed");
    }
    for (auto it = current.begin(); it != current.end(); ++it)
        if (!recorded.contains(it.key())) changes.push_back(it.key() + " is a new input");
    std::string out;
    for (const std::string& c : changes) out += (out.empty() ? "" : ", ") + c;
    return out;
}

namespace {

// The first few JSON-pointer paths at which two configurations differ.
std::string config_differences(const Json& recorded, const Json& current) {
    const Json patch = Json::diff(recorded, current);
    std::string out;
    int shown = 0;
    for (const Json& op : patch) {
        if (shown == 4) {
            out += ", ...";
            break;
        }
        std::string path = op.value("path", std::string());
        std::replace(path.begin(), path.end(), '/', '.');
        if (!path.empty() && path.front() == '.') path.erase(0, 1);
        out += (shown++ ? ", " : "") + path;
    }
    return out;
}

}  // namespace

void verify_resume(const std::string& checkpoint_path, const std::string& resolved_config,
                   const Json& inputs) {
    if (!fs::exists(checkpoint_path))
        throw_error("--resume: no checkpoint at '{}' (start without --resume)", checkpoint_path);
    const FieldCheckpoint checkpoint = load_field_checkpoint(checkpoint_path);
    const Json extra = parse_json(checkpoint.extra, checkpoint_path);
    if (!extra.contains("config") || !extra["config"].is_string())
        throw_error("--resume: '{}' records no configuration", checkpoint_path);
    const std::string recorded_config = extra["config"].get<std::string>();
    if (recorded_config != resolved_config)
        throw_error(
            "--resume: '{}' was written with a different scene or configuration (differs at: {}); start "
            "without --resume or restore the old settings",
            checkpoint_path,
            config_differences(parse_json(recorded_config, checkpoint_path),
                               parse_json(resolved_config, "")));
    if (!extra.contains("inputs")) {
        log_warning("--resume: '{}' records no input hashes (older tdf); the input files are not verified",
                    checkpoint_path);
        return;
    }
    const std::string changes = describe_input_changes(extra["inputs"], inputs);
    if (!changes.empty())
        throw_error(
            "--resume: input files changed since '{}' was written: {}; start without --resume or restore "
            "them",
            checkpoint_path,
            changes);
}

// ---- completion record --------------------------------------------------------------------

std::string completion_record_path(const std::string& folder, const std::string& name) {
    return (fs::path(folder) / (name + "_complete.json")).string();
}

namespace {

std::string validated_folder(const std::string& output_dir, const std::string& name) {
    validate_output_target(output_dir, name);
    return output_dir;
}


}  // namespace

RunGuard::RunGuard(const std::string& output_dir, const std::string& name, const std::string& command)
    : m_folder(validated_folder(output_dir, name)),
      m_name(name),
      m_command(command),
      m_lock(m_folder, command),
      m_start(std::chrono::steady_clock::now()) {
    const std::vector<std::string> removed = remove_stale_temporaries(m_folder);
    if (!removed.empty())
        log_info("removed {} temporary file(s) an interrupted run left in {} (e.g. {})",
                 removed.size(),
                 m_folder,
                 fs::path(removed.front()).filename().string());
    std::error_code ignored;
    fs::remove(completion_record_path(m_folder, m_name), ignored);
}

double RunGuard::seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
}

void RunGuard::complete(const Json& extra) const {
    const std::string record_path = completion_record_path(m_folder, m_name);
    const fs::path record_name = fs::path(record_path).filename();
    Json files = Json::array();
    std::vector<fs::path> paths;
    for (const auto& entry : fs::recursive_directory_iterator(m_folder)) {
        const std::string file_name = entry.path().filename().string();
        if (!entry.is_regular_file() || file_name == kLockFileName ||
            entry.path().filename() == record_name || is_atomic_temporary(file_name))
            continue;
        paths.push_back(entry.path());
    }
    std::sort(paths.begin(), paths.end());
    // FNV-1a is one serial chain per file (a few cycles a byte, 170 MB for the main job):
    // the files are hashed side by side.
    std::vector<std::uint64_t> hashes(paths.size());
    parallel_for(paths.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) hashes[k] = hash_file(paths[k].string());
    });
    for (std::size_t k = 0; k < paths.size(); ++k)
        files.push_back({{"path", fs::relative(paths[k], m_folder).generic_string()},
                         {"bytes", fs::file_size(paths[k])},
                         {"fnv1a", hash_hex(hashes[k])}});
    Json record = {{"command", m_command},
                   {"name", m_name},
                   {"seconds", seconds()},
                   {"finished", utc_timestamp()},
                   {"files", files}};
    for (auto it = extra.begin(); it != extra.end(); ++it) record[it.key()] = *it;
    write_text_atomically(record_path, record.dump(2) + "\n");
}

std::string utc_timestamp() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

}  // namespace tdf
