// Internal to the parameter table (params.cpp and its row files): a row under construction and
// the functions that add each stage's rows, so no one file holds the whole table.
#pragma once

#include <algorithm>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "bounce/config/params.h"

namespace bounce::param_rows {

using nlohmann::json;

/// A row bound to one field of one stage's settings struct. The type follows the field's.
template <class Group, class T>
Param field(const char* key, const char* stage, Group RenderSettings::*group, T Group::*member) {
    Param p;
    p.key = std::string("render.") + key;
    p.stage = stage;
    if constexpr (std::is_same_v<T, int>)
        p.type = ParamType::Int;
    else if constexpr (std::is_same_v<T, uint64_t>)
        p.type = ParamType::UInt64;
    else if constexpr (std::is_same_v<T, float>)
        p.type = ParamType::Float;
    else if constexpr (std::is_same_v<T, bool>)
        p.type = ParamType::Bool;
    else if constexpr (std::is_same_v<T, std::string>)
        p.type = ParamType::Path;
    else if constexpr (std::is_enum_v<T>)
        p.type = ParamType::Enum;
    else {
        p.type = ParamType::IntList;
        p.count = std::tuple_size_v<T>;
    }
    p.get = [group, member](ParamsIn s) -> json {
        const T& v = s.render.*group.*member;
        if constexpr (std::is_enum_v<T>)
            return static_cast<int>(v);  // named by Row::choices
        else
            return v;
    };
    p.set = [group, member](ParamsOut s, const json& v) {
        T& dst = s.render.*group.*member;
        if constexpr (std::is_enum_v<T>)
            dst = static_cast<T>(v.get<int>());
        else
            dst = v.get<T>();
    };
    return p;
}

/// Chained setters keep each row of the table on a few readable lines.
struct Row {
    Param p;
    Row& range(double lo, double hi) {
        p.lo = lo, p.hi = hi;
        return *this;
    }
    Row& unit(const char* u) {
        p.unit = u;
        return *this;
    }
    Row& doc(const char* d) {
        p.doc = d;
        return *this;
    }
    Row& id(unsigned mask) {
        p.identity = mask;
        return *this;
    }
    Row& animate() {
        p.animatable = true;
        return *this;
    }
    /// The CLI flag: "--" and the key's name with dashes, unless given.
    Row& flag(std::string f = "") {
        if (f.empty()) {
            f = "--" + p.name();
            for (char& c : f) c = c == '_' ? '-' : c;
        }
        p.flag = f;
        return *this;
    }
    Row& automatic(float sentinel) {  // a float whose sentinel value reads "auto"
        p.type = ParamType::FloatAuto;
        auto get = p.get;
        auto set = p.set;
        p.get = [get, sentinel](ParamsIn s) -> json {
            json v = get(s);
            return v.get<float>() == sentinel ? json("auto") : v;
        };
        p.set = [set, sentinel](ParamsOut s, const json& v) { set(s, v.is_string() ? json(sentinel) : v); };
        return *this;
    }
    Row& choices(std::vector<std::string> names) {
        p.choices = names;
        auto get = p.get;
        auto set = p.set;
        p.get = [get, names](ParamsIn s) -> json { return names.at(get(s).get<size_t>()); };
        p.set = [set, names](ParamsOut s, const json& v) {
            auto it = std::find(names.begin(), names.end(), v.get<std::string>());
            set(s, static_cast<int>(it - names.begin()));
        };
        return *this;
    }
};

template <class Group, class T>
Row row(const char* key, const char* stage, Group RenderSettings::*group, T Group::*member) {
    return Row{field(key, stage, group, member)};
}

/// The rows of each stage, appended in the order `bounce params` lists them.
void add_camera_rows(std::vector<Row>& rows);
void add_pipeline_rows(std::vector<Row>& rows);  ///< visibility, dicing, lighting, radiosity, gather
void add_cache_rows(std::vector<Row>& rows);
void add_output_rows(std::vector<Row>& rows);  ///< shading, parallel

}  // namespace bounce::param_rows
