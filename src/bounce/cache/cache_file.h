// Irradiance cache files (.bic): versioned, self-describing, checksummed per block, written
// atomically. Format: docs/cache-format.md. Readers never trust a count before checking it
// against the file size, so a hostile file cannot make them allocate without bound.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "bounce/cache/record.h"

namespace bounce {

/// What a cache file holds besides its records.
struct CacheFileInfo {
    uint64_t scene_fingerprint = 0;   ///< Scene::fingerprint({"objects","materials","lights"})
    uint64_t camera_fingerprint = 0;  ///< Scene::fingerprint({"camera"})
    /// Scene::fingerprint({"objects"}): where records lie and what their rays can hit (0: not
    /// known, a file from before it was written). Equal while scene_fingerprint differs: only
    /// lights or materials changed, so the records still fit the scene and hold its old light.
    uint64_t geometry_fingerprint = 0;
    /// scene_fingerprint with every light's colour and intensity left out (Scene::
    /// unscaled_fingerprint): equal while only those differ, records that keep light parts
    /// take the new ones exactly (0: not known, a file from before version 5).
    uint64_t unscaled_fingerprint = 0;
    nlohmann::json parameters = nlohmann::json::object();  ///< the settings that made it
    float luminance_floor = 0;
    int frame = 0;
};

struct CacheFile {
    CacheFileInfo info;
    std::vector<Record> records;
    /// Per-fragment refinement's records: each belongs to one fragment (Record::key, at
    /// exactly Record::p) and no lookup sees it. Stored after `records`.
    std::vector<Record> fragment_records;
};

/// 2: records carry their gather's origin, view summary (reach), anchor, last gather frame and drift.
/// 3: ... and their gather's noise (Record::noise, for refinement's spread).
/// 4: ... and per-fragment refinement's records.
/// 5: ... and, when every record keeps them, the records' light parts (render.light_parts), with
///    the scene's fingerprint without the lights' colours and intensities. 4 is still read.
inline constexpr uint32_t kCacheFileVersion = 5;

/// Whether every record of `file` (fragment records too) keeps its light parts for `lights`
/// lights: only then are parts written, and a loaded cache rescales exactly.
bool keeps_light_parts(const CacheFile& file, size_t lights);

/// Writes `file` to `path` (temporary name, then rename).
void write_cache_file(const std::string& path, const CacheFile& file);
/// Reads a cache file; InputError naming the file and the place on anything malformed.
CacheFile read_cache_file(const std::string& path);
/// Parses cache-file bytes (the fuzz target's entry); `name` is used in errors.
CacheFile parse_cache_file(const std::string& bytes, const std::string& name);
/// Serialises to bytes.
std::string serialize_cache_file(const CacheFile& file);

/// Records with their gather hits, as bytes for another process of the same build (an MPI
/// exchange; not a file format), and back.
std::string serialize_records(std::span<const Record> records);
std::vector<Record> parse_records(const std::string& bytes);

/// The record layout this version writes, as (name, type, count) triples for the header.
nlohmann::json record_layout();

/// Expands a frame pattern: each run of '#' becomes the zero-padded frame number.
std::string expand_frame_pattern(const std::string& pattern, int frame);

}  // namespace bounce
