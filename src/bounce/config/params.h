// The parameter table: every camera and render setting, declared once with its name, type,
// range, unit, one-line doc and the identity it belongs to. From this table (and nothing else)
// come the scene file's keys and their validation, `--set` overrides, the CLI flags
// (scene/params_cli.h), the deep-file and cache identities, the EXR metadata, `bounce params`,
// the Python module's `scene["render.rays"]` and the parameter table of docs/scene-format.md.
// Defaults are the settings structs' own (settings.h): a row reads them from a default camera
// and default settings. Rows read and write a camera and the render settings, not a Scene:
// the table sits below the world that holds them.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bounce/config/settings.h"
#include "bounce/geometry/camera.h"

namespace bounce {

/// What a change of the parameter invalidates (bit flags); 0 = the image only.
enum ParamIdentity : unsigned {
    kImageOnly = 0,
    kDeepIdentity = 1,       ///< primary visibility: needs a new deep file
    kRadiosityIdentity = 2,  ///< baked radiosity textures
    kCacheIdentity = 4,      ///< irradiance-cache records: needs a re-gather
};

/// What a row reads: the camera and the render settings (a Scene's: it converts).
struct ParamsIn {
    const Camera& camera;
    const RenderSettings& render;
    ParamsIn(const Camera& c, const RenderSettings& r) : camera(c), render(r) {}
    template <class S>
    ParamsIn(const S& s) : ParamsIn(s.camera, s.render) {}  // NOLINT: implicit, so a Scene is passed as it is
};
/// What a row writes.
struct ParamsOut {
    Camera& camera;
    RenderSettings& render;
    ParamsOut(Camera& c, RenderSettings& r) : camera(c), render(r) {}
    template <class S>
    ParamsOut(S& s) : ParamsOut(s.camera, s.render) {}  // NOLINT: implicit, so a Scene is passed as it is
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
    std::function<nlohmann::json(ParamsIn)> get;
    std::function<void(ParamsOut, const nlohmann::json&)> set;  ///< takes a validated value

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

/// The value of row `key` ("render.gi" -> "cache"), as the scene file writes it: how a front end
/// (the CLI, the lighting tool, Python) reads a setting. std::out_of_range for a key not in the table.
nlohmann::json param_value(ParamsIn s, const std::string& key);
/// Sets row `key` to `v`, checked as a scene file's value is; std::invalid_argument with the
/// table's message when it is not a value of the row, std::out_of_range for a key not in the table.
void set_param_value(ParamsOut s, const std::string& key, const nlohmann::json& v);

/// {key: value} of the rows whose identity has any bit of `mask` (all rows for ~0u).
nlohmann::json param_values(ParamsIn scene, unsigned mask, const ParamTable& table = scene_params());

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
