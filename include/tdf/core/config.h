#pragma once
/// Scene and run configuration: JSON files, `key=value` command-line overrides, and a reader
/// that rejects unknown keys (a typo must not silently fall back to a default).
///
/// Overrides use dotted paths into the JSON: `image.width=256`, `views.mode=turntable`,
/// `seed=7`. The value is parsed as JSON when it can be (numbers, true/false, arrays,
/// quoted strings) and taken as a plain string otherwise (`mesh=meshes/cow.obj`).
#include <cstdint>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace tdf {

using Json = nlohmann::json;

/// Parses `text` (the contents of `source`, used in error messages). Duplicate keys in one
/// object and numbers out of double range (`1e999`) are errors naming `source`.
Json parse_json(const std::string& text, const std::string& source);
/// Reads and parses a JSON file. A top-level "parent" key names a file (relative to this one)
/// whose keys this file extends; objects merge recursively, other values replace.
Json load_json_file(const std::string& path);
/// Applies one `dotted.key=value` override; throws tdf::Error on a malformed override.
void apply_override(Json& config, const std::string& assignment);

/// Typed access to one JSON object that remembers which keys were read.
class ConfigReader {
public:
    /// `where` names the object in messages, e.g. "scenes/cow.json: views".
    ConfigReader(const Json& object, std::string where);

    bool has(const std::string& key) const;
    /// The value of `key` converted to T, or `fallback` when absent. Throws tdf::Error naming
    /// the key and the expected type when the value has the wrong type.
    template <typename T>
    T get(const std::string& key, const T& fallback);
    /// Like get() but the key must be present.
    template <typename T>
    T require(const std::string& key);
    /// A reader for the object at `key` (an empty object when absent).
    ConfigReader child(const std::string& key);
    /// The raw JSON of `key` (marks it read).
    const Json& raw(const std::string& key);
    /// Throws tdf::Error listing every key that was never read (unknown or misspelt keys).
    void check_all_read() const;
    const std::string& where() const { return m_where; }

private:
    [[noreturn]] void type_error(const std::string& key, const char* expected) const;
    [[noreturn]] void range_error(const std::string& key, const std::string& low,
                                  const std::string& high) const;

    const Json* m_object;
    std::string m_where;
    std::set<std::string> m_read;
    std::shared_ptr<Json> m_empty;
};

template <typename T>
T ConfigReader::get(const std::string& key, const T& fallback) {
    if (!has(key)) {
        m_read.insert(key);
        return fallback;
    }
    return require<T>(key);
}

template <typename T>
T ConfigReader::require(const std::string& key) {
    const Json& value = raw(key);
    try {
        if constexpr (std::is_same_v<T, bool>) {
            if (!value.is_boolean()) type_error(key, "true or false");
        } else if constexpr (std::is_integral_v<T>) {
            if (!value.is_number_integer()) type_error(key, "an integer");
            // nlohmann converts out-of-range integers silently (2^64 - 1 read as int64 is -1).
            bool fits;
            if (value.is_number_unsigned()) {
                fits = value.template get<std::uint64_t>() <= std::uint64_t(std::numeric_limits<T>::max());
            } else {
                const std::int64_t v = value.template get<std::int64_t>();
                if constexpr (std::is_signed_v<T>)
                    fits = v >= std::int64_t(std::numeric_limits<T>::min()) &&
                           v <= std::int64_t(std::numeric_limits<T>::max());
                else
                    fits = v >= 0 && std::uint64_t(v) <= std::uint64_t(std::numeric_limits<T>::max());
            }
            if (!fits)
                range_error(key,
                            std::to_string(std::numeric_limits<T>::min()),
                            std::to_string(std::numeric_limits<T>::max()));
        } else if constexpr (std::is_floating_point_v<T>) {
            if (!value.is_number()) type_error(key, "a number");
        } else if constexpr (std::is_same_v<T, std::string>) {
            if (!value.is_string()) type_error(key, "a string");
        }
        return value.get<T>();
    } catch (const nlohmann::json::exception&) {
        type_error(key, "a value of another type");
    }
}

}  // namespace tdf
