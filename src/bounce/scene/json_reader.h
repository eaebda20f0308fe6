// Reading JSON scene text: parsing (line:column errors, duplicate keys refused), the `--set`
// override engine, and a validating reader that names the JSON pointer of every bad value.
// Values that came from the command line are blamed on the flag that gave them.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bounce/core/json_values.h"
#include "bounce/core/math.h"
#include "bounce/scene/load_resources.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// An override of the scene file: "dotted.path=value" (value is JSON; a bare word is a string),
/// how the user wrote it ("--set render.rays=-1", "--rays -1") and where (the command line, or
/// the lighting tool's edit requests): errors name both, not the scene file.
struct Override {
    std::string assignment;
    std::string origin;
    std::string source = "command line";
    /// A relative folder it sets is the scene folder's (an edit in the lighting tool, saved into
    /// the scene), not the working directory's (a flag or --set in a shell).
    bool scene_relative = false;
    Override(std::string a) : assignment(std::move(a)), origin("--set " + assignment) {}  // NOLINT: implicit by design
    Override(const char* a) : Override(std::string(a)) {}                                 // NOLINT
    Override(std::string a, std::string o) : assignment(std::move(a)), origin(std::move(o)) {}
    Override(std::string a, std::string o, std::string s) : assignment(std::move(a)), origin(std::move(o)), source(std::move(s)) {}
};

/// Where values come from: the file, its folder, and the pointers set on the command line.
struct JsonContext {
    std::string file;
    std::filesystem::path dir;
    std::map<std::string, Override> overridden;  ///< JSON pointer -> the override that set it
    /// Every file JsonReader::file resolves is appended here (null: not recorded).
    std::vector<SceneInput>* inputs = nullptr;
    /// LoadOptions::check_path: sees every file and folder path before it is used.
    std::function<void(const std::string& path, const std::string& pointer)> check_path;
    LoadResources resources;  ///< LoadOptions::resources: handed to every mesh file's load

    /// Pointers whose value came from keys, and the frame they were taken at: an error there
    /// names the frame (a keyed fov that leaves its range at frame 3).
    std::vector<std::string> keyed;
    double frame = 0;
    /// Throws InputError at `ptr`, blaming the override's source when one set it.
    [[noreturn]] void fail(const std::string& ptr, const std::string& msg) const;
    /// A relative path at `ptr` is the working directory's: a --set or flag set it.
    bool relative_to_working_dir(const std::string& ptr) const {
        const auto it = overridden.find(ptr);
        return it != overridden.end() && !it->second.scene_relative;
    }
};

/// The text of a regular file; "is a directory" / "not a regular file" (FIFOs, devices) are
/// refused before opening, so nothing blocks.
std::string read_text_file(const std::string& path);
/// Parses JSON text; errors carry line:column; a key given twice in one object is an error.
nlohmann::json parse_json_text(const std::string& text, const std::string& path);
/// Applies an override to `doc`; returns the JSON pointer it set.
std::string apply_override(nlohmann::json& doc, const Override& o);

/// A JSON object whose keys must be among `allowed` (unknown keys fail with a suggestion).
class JsonReader {
  public:
    JsonReader(const nlohmann::json& j, std::string ptr, const JsonContext& ctx, std::vector<std::string> allowed);

    std::string at(const std::string& key) const { return ptr_ + "/" + key; }
    bool has(const std::string& key) const { return j_.contains(key); }
    const nlohmann::json& raw(const std::string& key) const { return j_.at(key); }
    [[noreturn]] void fail(const std::string& key, const std::string& msg) const { ctx_.fail(key.empty() ? ptr_ : at(key), msg); }
    const JsonContext& ctx() const { return ctx_; }
    const std::string& pointer() const { return ptr_; }

    /// A number checked as the float it becomes: finite, representable, inside [lo, hi].
    float number(const std::string& key, float def, double lo = -kMaxCoordinate, double hi = kMaxCoordinate, bool required = false) const;
    int integer(const std::string& key, int def, int lo, int hi) const;
    /// A point or vector: three floats within +-kMaxCoordinate.
    Vec3 vec3(const std::string& key, Vec3 def, bool required = false) const;
    /// A colour: [r,g,b] or one number for grey; components in [0, 1e20].
    Color color(const std::string& key, Color def) const;
    std::string string(const std::string& key, const std::string& def, bool required = false) const;
    bool boolean(const std::string& key, bool def) const;
    std::string choice(const std::string& key, const std::string& def, const std::vector<std::string>& options) const;
    /// A file name, resolved against the scene's folder; must be a regular file. Recorded in
    /// the context's inputs.
    std::string file(const std::string& key, bool required) const;

    float check_number(const nlohmann::json& v, const std::string& ptr, double lo, double hi) const;
    /// Fails on the first key outside `keys`: "does not apply to `what` (its keys: ...)".
    void only(const std::vector<std::string>& keys, const std::string& what) const;
    Vec3 to_vec3(const nlohmann::json& v, const std::string& ptr) const;

  private:
    const nlohmann::json& j_;
    std::string ptr_;
    const JsonContext& ctx_;
};

}  // namespace bounce
