#include "bounce/core/json_limits.h"

#include <fmt/format.h>

#include "bounce/core/error.h"

namespace bounce {

void check_json_nesting(std::string_view text, const std::string& origin, int max_depth) {
    int depth = 0;
    bool in_string = false, escaped = false;
    size_t line = 1, col = 0;
    for (char c : text) {
        ++col;
        if (c == '\n') ++line, col = 0;
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                in_string = false;
            continue;
        }
        if (c == '"')
            in_string = true;
        else if (c == '[' || c == '{') {
            if (++depth > max_depth)
                throw InputError(origin, fmt::format("{}:{}", line, col), fmt::format("JSON nested deeper than {} levels", max_depth));
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
}

}  // namespace bounce
