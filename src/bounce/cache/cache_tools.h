// What `bounce cache` does with cache files: inspect, merge without duplicates, filter by
// region or value, export as a point cloud. Library calls; the CLI only parses options.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "bounce/cache/cache_file.h"

namespace bounce {

/// Counts, bounds, parameters, radius-in-pixels histogram, memory, records per frame.
nlohmann::json cache_info(const CacheFile& file, size_t file_bytes);
/// Human-readable form of cache_info.
std::string cache_info_text(const nlohmann::json& info, const std::string& path);

/// Union of two caches without duplicates, independent of argument order: records are taken
/// in a canonical order, and one is dropped when records already kept from the *other* input
/// cover it (weights sum >= min_weight under `a`'s settings). Merging a cache with itself
/// gives it back. Throws InputError if the caches belong to different scenes or cameras.
CacheFile merge_caches(const CacheFile& a, const CacheFile& b, const std::string& name_a, const std::string& name_b, bool force);

/// One --where term, parsed: a record field compared with a number.
struct WhereTerm {
    enum class Field { PX, PY, PZ, NX, NY, NZ, ER, EG, EB, EY, Ao, Radius, Pixels, Rays, Frame };
    enum class Op { Less, LessEqual, Greater, GreaterEqual, Equal, NotEqual };
    Field field = Field::Radius;
    Op op = Op::Less;
    double value = 0;
    /// Parses "field op value": fields p.x p.y p.z n.x .. E.r E.g E.b E.y (luminance) ao radius
    /// pixels (radius / footprint) rays frame; ops < <= > >= == !=. Throws InputError naming
    /// `term` on a bad one.
    static WhereTerm parse(const std::string& term);
    bool holds(const Record& r) const;
};

/// A record predicate for `cache filter`.
struct RecordFilter {
    bool has_box = false, has_sphere = false;
    Vec3 box_lo, box_hi, center;
    float radius = 0;
    std::vector<WhereTerm> where;  ///< all must hold
    bool matches(const Record& r) const;
};

/// Keeps the records matching `filter` (or removes them when `remove`).
CacheFile filter_cache(const CacheFile& in, const RecordFilter& filter, bool remove);

/// Who asks a tool to write a file, for its refusals: the CLI ("command line", "-o PATH",
/// "cache merge") or Python ("python", "merge(output='PATH')", "merge()").
struct ToolCall {
    std::string source, output_place, command;
};
/// InputError(call) unless `output` ends in `extension` (a scene or an image named by mistake
/// is never overwritten) and names none of `inputs` (check_output_file).
void check_tool_output(const ToolCall& call, const std::string& output, const char* extension, const char* what,
                       const std::vector<std::string>& inputs);
/// `bounce cache merge`: the cache files `inputs` (two or more) merged into `output`.
CacheFile merge_cache_files(const ToolCall& call, const std::vector<std::string>& inputs, const std::string& output, bool force);
/// `bounce cache filter`: the records of `input` that `filter` keeps (or removes), into `output`.
/// `filter` must say something (a box, a sphere or a where term); returns the input and output.
std::pair<CacheFile, CacheFile> filter_cache_file(const ToolCall& call, const std::string& input, const std::string& output,
                                                  const RecordFilter& filter, bool remove);

/// Writes a binary PLY point cloud: position, normal, tone-mapped irradiance colour, and the
/// raw irradiance, AO and radius as extra properties (MeshLab, CloudCompare, Blender).
void export_ply(const CacheFile& file, const std::string& path);

}  // namespace bounce
