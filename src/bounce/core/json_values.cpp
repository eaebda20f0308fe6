#include "bounce/core/json_values.h"

#include <fmt/format.h>

#include <cfloat>
#include <cmath>

namespace bounce {

using nlohmann::json;

const char* json_type_name(const json& j) {
    switch (j.type()) {
        case json::value_t::object:
            return "an object";
        case json::value_t::array:
            return "an array";
        case json::value_t::string:
            return "a string";
        case json::value_t::boolean:
            return "a boolean";
        case json::value_t::null:
            return "null";
        default:
            return "a number";
    }
}

float json_float(const json& v, double lo, double hi, const std::function<void(const std::string&)>& fail) {
    if (!v.is_number()) fail(fmt::format("expected a number, got {}", v.is_string() ? "a string (" + v.dump() + ")" : json_type_name(v)));
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail("number is not finite");
    if (std::fabs(x) > FLT_MAX) fail(fmt::format("{} does not fit a float", x));
    if (x < lo || x > hi) fail(fmt::format("{} is out of range [{}, {}]", x, lo, hi));
    return static_cast<float>(x);
}

int64_t json_integer(const json& v, double lo, double hi, const std::function<void(const std::string&)>& fail) {
    // 1e3 and 512.0 are whole numbers too; 2.5 is not.
    if (v.is_number_float()) {
        const double d = v.get<double>();
        if (!(std::isfinite(d) && d == std::floor(d))) fail(fmt::format("expected an integer, got {}", d));
        if (d < lo || d > hi) fail(fmt::format("{} is out of range [{}, {}]", d, lo, hi));
        return static_cast<int64_t>(d);
    }
    if (!v.is_number_integer()) fail(fmt::format("expected an integer, got {}", json_type_name(v)));
    if (v.is_number_unsigned() && v.get<uint64_t>() > static_cast<uint64_t>(INT64_MAX)) fail("integer is out of range");
    const int64_t x = v.get<int64_t>();
    if (static_cast<double>(x) < lo || static_cast<double>(x) > hi) fail(fmt::format("{} is out of range [{}, {}]", x, lo, hi));
    return x;
}

}  // namespace bounce
