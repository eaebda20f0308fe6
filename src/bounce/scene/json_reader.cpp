#include "bounce/scene/json_reader.h"

#include <fmt/format.h>

#include <cfloat>
#include <fstream>
#include <sstream>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/json_limits.h"

namespace bounce {

namespace fs = std::filesystem;
using nlohmann::json;

void JsonContext::fail(const std::string& ptr, const std::string& msg) const {
    for (const auto& [p, o] : overridden)
        if (ptr == p || ptr.rfind(p + "/", 0) == 0) throw InputError(o.source, o.origin + " (" + ptr + ")", msg);
    for (const std::string& k : keyed)
        if (ptr == k || ptr.rfind(k + "/", 0) == 0)
            throw InputError(file, ptr, fmt::format("{} (the value its keys give at frame {:g})", msg, frame));
    throw InputError(file, ptr.empty() ? "/" : ptr, msg);
}

std::string read_text_file(const std::string& path) {
    check_input_file(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open file for reading");
    std::stringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw InputError(path, "", "error while reading file");
    return ss.str();
}

namespace {

/// Builds the document as nlohmann's own DOM parser does (a SAX handler), and notes the first
/// key given twice in one object, which that parser keeps the last of silently. Each open
/// container knows its current key, so a duplicate's pointer is put together only when there
/// is one (a per-key set and name strings took most of a 14 400-placement scene's parse).
class DomBuilder {
  public:
    explicit DomBuilder(json& root) : root_(root) {}
    std::string duplicate;  ///< pointer of the first duplicate key

    bool null() { return add(nullptr); }
    bool boolean(bool v) { return add(v); }
    bool number_integer(json::number_integer_t v) { return add(v); }
    bool number_unsigned(json::number_unsigned_t v) { return add(v); }
    bool number_float(json::number_float_t v, const json::string_t&) { return add(v); }
    bool string(json::string_t& v) { return add(std::move(v)); }
    bool binary(json::binary_t& v) { return add(json::binary(std::move(v))); }
    bool start_object(std::size_t) { return open(json::object()); }
    bool start_array(std::size_t) { return open(json::array()); }
    bool end_object() { return close(); }
    bool end_array() { return close(); }
    bool key(json::string_t& k) {
        auto& object = open_.back().value->get_ref<json::object_t&>();
        auto [it, fresh] = object.try_emplace(k);
        if (!fresh && duplicate.empty()) duplicate = pointer() + "/" + k;
        open_.back().key = &it->first;
        element_ = &it->second;
        return true;
    }
    template <class Exception>
    bool parse_error(std::size_t, const std::string&, const Exception& e) {
        throw e;  // (as nlohmann's DOM parser: its type kept for the byte offset)
    }

  private:
    struct Open {
        json* value;
        const std::string* key = nullptr;  ///< an object's key being read
    };
    json& root_;
    std::vector<Open> open_;
    json* element_ = nullptr;  ///< where an object's next value goes

    json* place(json&& v) {
        if (open_.empty()) return &(root_ = std::move(v));
        json& parent = *open_.back().value;
        if (parent.is_array()) {
            parent.get_ref<json::array_t&>().push_back(std::move(v));
            return &parent.get_ref<json::array_t&>().back();
        }
        return &(*element_ = std::move(v));
    }
    bool add(json&& v) {
        place(std::move(v));
        return true;
    }
    bool open(json&& v) {
        open_.push_back({place(std::move(v))});
        return true;
    }
    bool close() {
        open_.pop_back();
        return true;
    }
    /// Pointer of the innermost open container: each level's key in its parent, or its index
    /// (the last element: an open container is its parent's last).
    std::string pointer() const {
        std::string p;
        for (size_t i = 1; i < open_.size(); ++i) {
            const Open& parent = open_[i - 1];
            p += "/" + (parent.value->is_array() ? std::to_string(parent.value->size() - 1) : *parent.key);
        }
        return p;
    }
};

}  // namespace

json parse_json_text(const std::string& text, const std::string& path) {
    json doc;
    DomBuilder keys(doc);
    check_json_nesting(text, path);
    try {
        json::sax_parse(text, &keys);
    } catch (const json::parse_error& e) {
        size_t line = 1, col = 1;
        for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
            if (text[i] == '\n')
                ++line, col = 1;
            else
                ++col;
        }
        std::string msg = e.what();
        auto pos = msg.find(": ", msg.find("column"));
        if (pos != std::string::npos) msg = msg.substr(pos + 2);
        throw InputError(path, fmt::format("{}:{}", line, col), "malformed JSON: " + msg);
    } catch (const json::exception& e) {  // e.g. a number that overflows a double
        std::string msg = e.what();
        auto pos = msg.find("] ");
        throw InputError(path, "", "malformed JSON: " + (pos == std::string::npos ? msg : msg.substr(pos + 2)));
    }
    if (!keys.duplicate.empty()) throw InputError(path, keys.duplicate, "key given twice in one object");
    return doc;
}

std::string apply_override(json& doc, const Override& o) {
    const std::string& assignment = o.assignment;
    auto fail = [&](const std::string& msg) -> void { throw InputError(o.source, o.origin, msg); };
    auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0) fail("expected key=value");
    std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
    std::vector<std::string> parts;
    std::string ptr;
    std::stringstream ks(key);
    for (std::string part; std::getline(ks, part, '.');) {
        if (part.empty()) fail("empty path component");
        parts.push_back(part);
        ptr += "/" + part;
    }
    if (key.back() == '.') fail("empty path component");
    json value;
    check_json_nesting(text, o.origin);
    try {
        value = json::parse(text);
    } catch (const json::parse_error&) {
        value = text;  // a bare word is a string
    } catch (const json::out_of_range&) {
        throw InputError(o.source, o.origin + " (" + ptr + ")", "number is not finite: " + text);
    }
    json* node = &doc;
    for (size_t i = 0; i < parts.size(); ++i) {
        const std::string& part = parts[i];
        if (node->is_array()) {
            if (part.empty() || part.size() > 9 || !std::all_of(part.begin(), part.end(), ::isdigit))
                fail("\"" + part + "\" is not an array index");
            size_t idx = std::stoul(part);
            if (idx >= node->size()) fail(fmt::format("index {} is out of range (array has {} items)", idx, node->size()));
            node = &(*node)[idx];
        } else {
            // An index into nothing: the scene has no such list ("lights.0" without lights).
            const bool index = !part.empty() && part.size() <= 9 && std::all_of(part.begin(), part.end(), ::isdigit);
            if (node->is_null() && index) fail(fmt::format("the scene has no \"{}\" list to index", i > 0 ? parts[i - 1] : std::string()));
            if (node->is_null()) *node = json::object();
            if (!node->is_object()) fail("\"" + part + "\" is inside a value that is not an object");
            node = &(*node)[part];
        }
    }
    *node = value;
    return ptr;
}

JsonReader::JsonReader(const json& j, std::string ptr, const JsonContext& ctx, std::vector<std::string> allowed)
    : j_(j), ptr_(std::move(ptr)), ctx_(ctx) {
    if (!j_.is_object()) ctx_.fail(ptr_, fmt::format("expected an object, got {}", json_type_name(j_)));
    for (auto it = j_.begin(); it != j_.end(); ++it) {
        if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
        std::string hint = closest_match(it.key(), allowed);
        ctx_.fail(at(it.key()), fmt::format("unknown key \"{}\"{}", it.key(),
                                            hint.empty() ? fmt::format(" (valid keys: {})", fmt::join(allowed, ", "))
                                                         : " (did you mean \"" + hint + "\"?)"));
    }
}

float JsonReader::number(const std::string& key, float def, double lo, double hi, bool required) const {
    if (!has(key)) {
        if (required) fail("", fmt::format("missing required key \"{}\"", key));
        return def;
    }
    return check_number(raw(key), at(key), lo, hi);
}

int JsonReader::integer(const std::string& key, int def, int lo, int hi) const {
    if (!has(key)) return def;
    return static_cast<int>(json_integer(raw(key), lo, hi, [&](const std::string& m) { ctx_.fail(at(key), m); }));
}

Vec3 JsonReader::vec3(const std::string& key, Vec3 def, bool required) const {
    if (!has(key)) {
        if (required) fail("", fmt::format("missing required key \"{}\"", key));
        return def;
    }
    return to_vec3(raw(key), at(key));
}

Color JsonReader::color(const std::string& key, Color def) const {
    if (!has(key)) return def;
    const json& v = raw(key);
    if (v.is_number()) return Color(check_number(v, at(key), 0, kMaxRadiometric));
    if (!v.is_array() || v.size() != 3)
        ctx_.fail(at(key), fmt::format("expected an array of 3 numbers or one number, got {}", json_type_name(v)));
    Color c;
    for (int i = 0; i < 3; ++i) {
        std::string p = at(key) + "/" + std::to_string(i);
        c[i] = check_number(v[static_cast<size_t>(i)], p, -kMaxRadiometric, kMaxRadiometric);
        if (c[i] < 0) ctx_.fail(p, "colour components must be >= 0");
    }
    return c;
}

std::string JsonReader::string(const std::string& key, const std::string& def, bool required) const {
    if (!has(key)) {
        if (required) fail("", fmt::format("missing required key \"{}\"", key));
        return def;
    }
    const json& v = raw(key);
    if (!v.is_string()) ctx_.fail(at(key), fmt::format("expected a string, got {}", json_type_name(v)));
    return v.get<std::string>();
}

bool JsonReader::boolean(const std::string& key, bool def) const {
    if (!has(key)) return def;
    const json& v = raw(key);
    if (!v.is_boolean()) ctx_.fail(at(key), fmt::format("expected true or false, got {}", json_type_name(v)));
    return v.get<bool>();
}

std::string JsonReader::choice(const std::string& key, const std::string& def, const std::vector<std::string>& options) const {
    std::string s = string(key, def, def.empty());
    if (std::find(options.begin(), options.end(), s) == options.end())
        ctx_.fail(at(key), fmt::format("unknown value \"{}\" (valid: {})", s, fmt::join(options, ", ")));
    return s;
}

std::string JsonReader::file(const std::string& key, bool required) const {
    std::string s = string(key, "", required);
    // A key written in the file with no name is a mistake (a texture left out by accident), not
    // "none"; --set key="" is how a flag clears one.
    if (s.empty() && has(key) && !ctx_.overridden.count(at(key))) ctx_.fail(at(key), "an empty file name (leave the key out for none)");
    if (s.empty()) return s;
    fs::path p = fs::path(s).is_absolute() ? fs::path(s) : ctx_.dir / s;
    if (ctx_.check_path) ctx_.check_path(p.lexically_normal().string(), at(key));
    if (std::string why = not_a_regular_file(p.string()); !why.empty()) ctx_.fail(at(key), fmt::format("{}: \"{}\"", why, p.string()));
    const std::string path = p.lexically_normal().string();
    if (ctx_.inputs) ctx_.inputs->push_back({path, at(key)});
    return path;
}

void JsonReader::only(const std::vector<std::string>& keys, const std::string& what) const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
        if (std::find(keys.begin(), keys.end(), it.key()) == keys.end())
            ctx_.fail(at(it.key()), fmt::format("\"{}\" does not apply to {} (its keys: {})", it.key(), what, fmt::join(keys, ", ")));
}

float JsonReader::check_number(const json& v, const std::string& ptr, double lo, double hi) const {
    return json_float(v, lo, hi, [&](const std::string& m) { ctx_.fail(ptr, m); });
}

Vec3 JsonReader::to_vec3(const json& v, const std::string& ptr) const {
    if (!v.is_array() || v.size() != 3) ctx_.fail(ptr, fmt::format("expected an array of 3 numbers, got {}", json_type_name(v)));
    Vec3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = check_number(v[static_cast<size_t>(i)], ptr + "/" + std::to_string(i), -kMaxCoordinate, kMaxCoordinate);
    return r;
}

}  // namespace bounce
