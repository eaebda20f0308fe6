#include "bounce/config/params.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/core/json_values.h"
#include "bounce/config/param_rows.h"

namespace bounce {

using nlohmann::json;

namespace {

ParamTable make_table() {
    std::vector<param_rows::Row> rows;
    param_rows::add_camera_rows(rows);
    param_rows::add_pipeline_rows(rows);
    param_rows::add_cache_rows(rows);
    param_rows::add_output_rows(rows);
    ParamTable table;
    for (auto& r : rows) {
        // A switch that is on by default is turned off on the command line.
        if (r.p.type == ParamType::Bool && !r.p.flag.empty() && r.p.default_value() == true) r.p.flag = "--no-" + r.p.flag.substr(2);
        table.push_back(std::move(r.p));
    }
    return table;
}

std::string type_name(const Param& p) {
    switch (p.type) {
        case ParamType::Int:
            return "integer";
        case ParamType::UInt64:
            return "unsigned integer";
        case ParamType::Float:
            return "number";
        case ParamType::FloatAuto:
            return "number or \"auto\"";
        case ParamType::Bool:
            return "boolean";
        case ParamType::Enum:
            return "enum";
        case ParamType::Path:
            return "path";
        case ParamType::Vec3:
            return "[x, y, z]";
        case ParamType::IntList:
            return fmt::format("{} integers", p.count);
        case ParamType::FloatList:
            return fmt::format("{} numbers", p.count);
    }
    return "";
}

/// A number checked as a float: finite, representable, inside [lo, hi].
float check_float(const json& v, double lo, double hi, const std::string& sub, const ParamFail& fail) {
    return json_float(v, lo, hi, [&](const std::string& m) { fail(sub, m); });
}

int64_t check_int(const json& v, double lo, double hi, const std::string& sub, const ParamFail& fail) {
    return json_integer(v, lo, hi, [&](const std::string& m) { fail(sub, m); });
}

}  // namespace

json Param::default_value() const { return get(ParamsIn(Camera{}, RenderSettings{})); }

const ParamTable& scene_params() {
    static const ParamTable table = make_table();
    return table;
}

const Param* find_param(const ParamTable& table, const std::string& key) {
    for (const Param& p : table)
        if (p.key == key) return &p;
    return nullptr;
}

json check_param(const Param& p, const json& v, const ParamFail& fail) {
    switch (p.type) {
        case ParamType::Int:
            return check_int(v, p.lo, p.hi, "", fail);
        case ParamType::UInt64:
            if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<int64_t>() >= 0))
                fail("", fmt::format("expected a non-negative integer, got {}", v.is_number() ? v.dump() : json_type_name(v)));
            return v.get<uint64_t>();
        case ParamType::FloatAuto:
            if (v.is_string() && v.get<std::string>() == "auto") return v;
            [[fallthrough]];
        case ParamType::Float:
            return check_float(v, p.lo, p.hi, "", fail);
        case ParamType::Bool:
            if (!v.is_boolean()) fail("", fmt::format("expected true or false, got {}", json_type_name(v)));
            return v;
        case ParamType::Enum:
        case ParamType::Path: {
            if (!v.is_string()) fail("", fmt::format("expected a string, got {}", json_type_name(v)));
            std::string s = v.get<std::string>();
            if (p.type == ParamType::Enum && std::find(p.choices.begin(), p.choices.end(), s) == p.choices.end())
                fail("", fmt::format("unknown value \"{}\" (valid: {})", s, fmt::join(p.choices, ", ")));
            return v;
        }
        case ParamType::Vec3:
        case ParamType::FloatList:
        case ParamType::IntList: {
            const bool floats = p.type != ParamType::IntList;
            size_t n = p.type == ParamType::Vec3 ? 3 : p.count;
            if (!v.is_array() || v.size() != n)
                fail("", fmt::format("expected an array of {} {}, got {}{}", n, floats ? "numbers" : "integers", json_type_name(v),
                                     v.is_array() ? fmt::format(" of {}", v.size()) : ""));
            json out = json::array();
            for (size_t i = 0; i < n; ++i) {
                const std::string sub = fmt::format("/{}", i);  // not "/" + to_string: GCC 12 -Wrestrict false positive
                if (floats)
                    out.push_back(check_float(v[i], p.lo, p.hi, sub, fail));
                else
                    out.push_back(check_int(v[i], p.lo, p.hi, sub, fail));
            }
            return out;
        }
    }
    return v;
}

namespace {
const Param& row_of(const std::string& key) {
    const Param* p = find_param(scene_params(), key);
    if (!p) throw std::out_of_range("no parameter named " + key);
    return *p;
}
}  // namespace

json param_value(ParamsIn s, const std::string& key) { return row_of(key).get(s); }

void set_param_value(ParamsOut s, const std::string& key, const json& v) {
    const Param& p = row_of(key);
    p.set(s, check_param(p, v, [](const std::string&, const std::string& msg) { throw std::invalid_argument(msg); }));
}

json param_values(ParamsIn scene, unsigned mask, const ParamTable& table) {
    json out = json::object();
    for (const Param& p : table)
        if (mask == ~0u || (p.identity & mask)) out[p.key] = p.get(scene);
    return out;
}

std::vector<std::string> param_differences(const json& was, const json& now) {
    std::vector<std::string> out;
    for (const auto& [key, value] : now.items()) {
        if (!was.contains(key))
            out.push_back(fmt::format("{}: (not recorded) -> {}", key, value.dump()));
        else if (was[key] != value)
            out.push_back(fmt::format("{}: {} -> {}", key, was[key].dump(), value.dump()));
    }
    for (const auto& [key, value] : was.items())
        if (!now.contains(key)) out.push_back(fmt::format("{}: {} -> (not a parameter)", key, value.dump()));
    return out;
}

std::string identity_names(unsigned mask) {
    std::vector<std::string> n;
    if (mask & kDeepIdentity) n.push_back("deep");
    if (mask & kRadiosityIdentity) n.push_back("radiosity");
    if (mask & kCacheIdentity) n.push_back("cache");
    return n.empty() ? "image" : fmt::format("{}", fmt::join(n, ","));
}

json params_listing(const ParamTable& table) {
    json out = json::array();
    for (const Param& p : table) {
        json j = {{"key", p.key},
                  {"stage", p.stage},
                  {"type", type_name(p)},
                  {"default", p.default_value()},
                  {"unit", p.unit},
                  {"doc", p.doc},
                  {"identity", identity_names(p.identity)},
                  {"flag", p.flag}};
        if (p.type == ParamType::Enum) j["choices"] = p.choices;
        if (p.lo != p.hi) j["range"] = {p.lo, p.hi};
        if (p.required) j["required"] = true;
        if (p.animatable) j["animatable"] = true;
        out.push_back(j);
    }
    return out;
}

std::string params_markdown(const ParamTable& table) {
    std::string s =
        "| key | type | default | range | unit | invalidates | animatable | CLI | meaning |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const Param& p : table) {
        std::string range = p.type == ParamType::Enum ? fmt::format("{}", fmt::join(p.choices, ", "))
                            : p.lo != p.hi            ? fmt::format("{:g} .. {:g}", p.lo, p.hi)
                                                      : "";
        std::string def = p.required ? "required" : p.default_value().dump();
        s += fmt::format("| `{}` | {} | `{}` | {} | {} | {} | {} | {} | {} |\n", p.key, type_name(p), def, range, p.unit,
                         identity_names(p.identity), p.animatable ? "yes" : "", p.flag.empty() ? "" : "`" + p.flag + "`", p.doc);
    }
    const json& items = animatable_item_keys();
    s += "\nAnimatable keys of the other items (keyframes, docs/animation.md):\n\n";
    for (const auto& [section, keys] : items.items())
        s += fmt::format("- `{}`: {}\n", section, fmt::format("`{}`", fmt::join(keys.get<std::vector<std::string>>(), "`, `")));
    return s;
}

const json& animatable_item_keys() {
    static const json keys = {{"lights",
                               {"color", "intensity", "position", "direction", "cone_angle", "cone_falloff", "cosine_power", "corner",
                                "edge_u", "edge_v", "rotation"}},
                              {"materials", {"color", "emission", "specular", "roughness", "bump_strength"}},
                              {"objects.transform", {"translate", "rotate", "scale"}}};
    return keys;
}

bool animatable_pointer(const std::string& ptr) {
    std::vector<std::string> parts;
    for (size_t at = 1; at <= ptr.size();) {
        const size_t next = std::min(ptr.find('/', at), ptr.size());
        parts.push_back(ptr.substr(at, next - at));
        at = next + 1;
    }
    const auto listed = [](const char* section, const std::string& key) {
        const json& k = animatable_item_keys()[section];
        return std::find(k.begin(), k.end(), key) != k.end();
    };
    if (parts.size() == 2 && parts[0] == "camera") {
        const Param* p = find_param(scene_params(), "camera." + parts[1]);
        return p && p->animatable;
    }
    if (parts.size() == 3 && parts[0] == "lights") return listed("lights", parts[2]);
    if (parts.size() == 3 && parts[0] == "materials") return listed("materials", parts[2]);
    if (parts.size() == 4 && parts[0] == "objects" && parts[2] == "transform") return listed("objects.transform", parts[3]);
    return false;
}

}  // namespace bounce
