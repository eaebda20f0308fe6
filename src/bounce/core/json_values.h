// One JSON value checked as the number it becomes, with the messages every reader of bounce's
// files (the scene file, the parameter table, the tool's requests) gives for a wrong one.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

namespace bounce {

/// "an object", "an array", "a string", "a boolean", "null" or "a number".
const char* json_type_name(const nlohmann::json& j);

/// `v` as the float it becomes: a finite number that fits a float, inside [lo, hi] (compared
/// before rounding); otherwise calls `fail(message)`, which must throw.
float json_float(const nlohmann::json& v, double lo, double hi, const std::function<void(const std::string&)>& fail);
/// `v` as an integer inside [lo, hi]; otherwise calls `fail(message)`, which must throw.
int64_t json_integer(const nlohmann::json& v, double lo, double hi, const std::function<void(const std::string&)>& fail);

}  // namespace bounce
