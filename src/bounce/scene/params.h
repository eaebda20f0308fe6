// The parameter table: every camera and render setting, declared once with its name, type,
// range, unit, one-line doc and the identity it belongs to. From this table (and nothing else)
// come the scene file's keys and their validation, `--set` overrides, the CLI flags
// (params_cli.h), the deep-file and cache identities, the EXR metadata, `bounce params` and
// the parameter table of docs/scene-format.md. Defaults are the settings structs' own
// (settings.h): a row reads them from a default-constructed scene.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bounce/scene/scene.h"

namespace bounce {

/// What a change of the parameter invalidates (bit flags); 0 = the image only.
enum ParamIdentity : unsigned {
    kImageOnly = 0,
    kDeepIdentity = 1,       ///< primary visibility: needs a new deep file
    kRadiosityIdentity = 2,  ///< baked radiosity textures
    kCacheIdentity = 4,      ///< irradiance-cache records: needs a re-gather
};

enum class ParamType { Int, UInt64, Float, FloatAuto, Bool, Enum, Path, Vec3, IntList, FloatList };

struct Param {
    std::string key;    ///< "render.min_spacing": the JSON path, the --set key, the name everywhere
    std::string stage;  ///< the settings struct it belongs to ("cache", "gather", ...)
    ParamType type = ParamType::Float;
    double lo = 0, hi = 0;             ///< numeric range (IntList: per element)
    std::vector<std::string> choices;  ///< Enum: the values, in enum order
    size_t count = 0;                  ///< IntList, FloatList: number of elements
    std::string unit, doc;
    unsigned identity = kImageOnly;
    std::string flag;  ///< CLI flag ("--min-spacing"); empty = only --set
    bool required = false;
    bool animatable = false;  ///< may be keyed in a shot (keyframes.h)
    std::function<nlohmann::json(const Scene&)> get;
    std::function<void(Scene&, const nlohmann::json&)> set;  ///< takes a validated value

    nlohmann::json default_value() const;
    /// The JSON key inside its section ("min_spacing") and the section ("render").
    std::string name() const { return key.substr(key.find('.') + 1); }
    std::string section() const { return key.substr(0, key.find('.')); }
};

using ParamTable = std::vector<Param>;

/// The table of all camera and render parameters.
const ParamTable& scene_params();
/// The row named `key` ("render.rays"), or nullptr.
const Param* find_param(const ParamTable& table, const std::string& key);

/// Checks `v` as a value of `p` in the type it will be used in (a float must fit a float) and
/// returns it normalised; on error calls `fail(suffix, message)`, which must throw (suffix is
/// "" or "/i" for an element).
using ParamFail = std::function<void(const std::string&, const std::string&)>;
nlohmann::json check_param(const Param& p, const nlohmann::json& v, const ParamFail& fail);

/// {key: value} of the rows whose identity has any bit of `mask` (all rows for ~0u).
nlohmann::json param_values(const Scene& scene, unsigned mask, const ParamTable& table = scene_params());

/// The differences between two param_values() objects, one "key: a -> b" string each.
std::vector<std::string> param_differences(const nlohmann::json& was, const nlohmann::json& now);

/// `bounce params --json`: one object per row (key, stage, type, default, range, unit, doc,
/// identity, flag).
nlohmann::json params_listing(const ParamTable& table = scene_params());
/// The Markdown table docs/scene-format.md carries between its params markers.
std::string params_markdown(const ParamTable& table = scene_params());

/// Names of the identities in `mask` ("deep", "radiosity", "cache"), or "image".
std::string identity_names(unsigned mask);

/// The keys of lights, materials and object transforms that may be keyed ("lights": [...] ...);
/// the camera's are the rows marked animatable.
const nlohmann::json& animatable_item_keys();
/// True when the value at JSON pointer `ptr` of a scene file ("/lights/0/position",
/// "/objects/2/transform/rotate", "/camera/fov") may be keyed.
bool animatable_pointer(const std::string& ptr);

}  // namespace bounce
