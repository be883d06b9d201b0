#include <tdf/core/atomic_file.h>
#include <tdf/core/config.h>
#include <tdf/core/error.h>

#include <filesystem>
#include <functional>

namespace tdf {

namespace {

// Duplicate keys are legal JSON but nlohmann keeps the last silently; a scene with two "mesh"
// keys is a mistake to report, not to guess at. The parser callback sees every key in order.
class DuplicateKeyCheck {
public:
    explicit DuplicateKeyCheck(std::string source) : m_source(std::move(source)) {}
    bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed) {
        switch (event) {
            case Json::parse_event_t::object_start:
                m_objects.emplace_back();
                break;
            case Json::parse_event_t::object_end:
                if (!m_objects.empty()) m_objects.pop_back();
                break;
            case Json::parse_event_t::key: {
                if (m_objects.empty()) break;
                Frame& frame = m_objects.back();
                frame.current = parsed.get<std::string>();
                if (!frame.keys.insert(frame.current).second) {
                    std::string path;
                    for (const auto& f : m_objects) path += (path.empty() ? "" : ".") + f.current;
                    throw_error("{}: duplicate key '{}'", m_source, path);
                }
                break;
            }
            default:
                break;
        }
        return true;
    }

private:
    struct Frame {
        std::set<std::string> keys;
        std::string current;
    };
    std::string m_source;  // a copy: callers pass temporaries (found by fuzzing)
    std::vector<Frame> m_objects;
};

// nlohmann's what() is "[json.exception.parse_error.101] parse error at line 3, column 5: ...";
// keep the part after the bracket.
std::string json_message(const nlohmann::json::exception& e) {
    const std::string what = e.what();
    const auto at = what.find("] ");
    return at == std::string::npos ? what : what.substr(at + 2);
}

}  // namespace

Json parse_json(const std::string& text, const std::string& source) {
    try {
        DuplicateKeyCheck check(source);
        return Json::parse(text, std::ref(check));
    } catch (const nlohmann::json::exception& e) {
        // Also out_of_range.406 for a number literal such as 1e999.
        throw_error("{}: invalid JSON: {}", source, json_message(e));
    }
}

namespace {
void merge_into(Json& base, const Json& overlay) {
    for (auto it = overlay.begin(); it != overlay.end(); ++it) {
        if (it->is_object() && base.contains(it.key()) && base[it.key()].is_object())
            merge_into(base[it.key()], *it);
        else
            base[it.key()] = *it;
    }
}

Json load_with_parents(const std::string& path, int depth) {
    if (depth > 8) throw_error("{}: \"parent\" chain is deeper than 8 files (a cycle?)", path);
    Json config = parse_json(read_text_file(path), path);
    if (!config.is_object()) throw_error("{}: the top level must be a JSON object", path);
    if (config.contains("parent")) {
        if (!config["parent"].is_string()) throw_error("{}: \"parent\" must be a file name", path);
        const auto parent_path =
            std::filesystem::path(path).parent_path() / config["parent"].get<std::string>();
        Json base = load_with_parents(parent_path.string(), depth + 1);
        config.erase("parent");
        merge_into(base, config);
        return base;
    }
    return config;
}
}  // namespace

Json load_json_file(const std::string& path) { return load_with_parents(path, 0); }

void apply_override(Json& config, const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw_error("override '{}' is not of the form key=value", assignment);
    // JSON text is UTF-8; a bare-string value or key that is not would make every later dump()
    // of the configuration throw (found by fuzzing).
    try {
        (void)Json(assignment).dump();
    } catch (const nlohmann::json::exception&) {
        throw_error("override '{}' is not valid UTF-8 text", assignment);
    }
    const std::string key = assignment.substr(0, eq);
    const std::string text = assignment.substr(eq + 1);
    Json value;
    try {
        DuplicateKeyCheck check("override '" + assignment + "'");
        value = Json::parse(text, std::ref(check));
    } catch (const Error&) {
        throw;
    } catch (const nlohmann::json::out_of_range& e) {
        throw_error("override '{}': {}", assignment, json_message(e));
    } catch (const nlohmann::json::exception&) {
        value = text;  // a bare string such as a path
    }
    Json* node = &config;
    std::size_t start = 0;
    while (true) {
        const auto dot = key.find('.', start);
        const std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
        if (part.empty()) throw_error("override '{}' has an empty key component", assignment);
        if (!node->is_object()) throw_error("override '{}': '{}' is not an object", assignment, part);
        if (dot == std::string::npos) {
            (*node)[part] = value;
            return;
        }
        node = &(*node)[part];
        if (node->is_null()) *node = Json::object();
        start = dot + 1;
    }
}

ConfigReader::ConfigReader(const Json& object, std::string where)
    : m_object(&object), m_where(std::move(where)) {
    if (!object.is_object() && !object.is_null()) throw_error("{}: expected a JSON object", m_where);
}

bool ConfigReader::has(const std::string& key) const {
    return m_object->is_object() && m_object->contains(key);
}

const Json& ConfigReader::raw(const std::string& key) {
    m_read.insert(key);
    if (!has(key)) throw_error("{}: missing required key '{}'", m_where, key);
    return (*m_object)[key];
}

ConfigReader ConfigReader::child(const std::string& key) {
    m_read.insert(key);
    if (!has(key)) {
        if (!m_empty) m_empty = std::make_shared<Json>(Json::object());
        ConfigReader reader(*m_empty, m_where + "." + key);
        reader.m_empty = m_empty;
        return reader;
    }
    const Json& value = (*m_object)[key];
    if (!value.is_object()) throw_error("{}: '{}' must be an object", m_where, key);
    return ConfigReader(value, m_where + "." + key);
}

void ConfigReader::check_all_read() const {
    if (!m_object->is_object()) return;
    std::string unknown;
    for (auto it = m_object->begin(); it != m_object->end(); ++it)
        if (!m_read.count(it.key())) unknown += (unknown.empty() ? "'" : ", '") + it.key() + "'";
    if (!unknown.empty()) throw_error("{}: unknown key(s) {}", m_where, unknown);
}

void ConfigReader::range_error(const std::string& key, const std::string& low,
                               const std::string& high) const {
    throw_error(
        "{}: '{}' must be an integer in [{}, {}], got {}", m_where, key, low, high, (*m_object)[key].dump());
}

void ConfigReader::type_error(const std::string& key, const char* expected) const {
    throw_error("{}: '{}' must be {}, got {}", m_where, key, expected, (*m_object)[key].dump());
}

}  // namespace tdf
