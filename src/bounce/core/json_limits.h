// Limits on JSON text before any parser sees it: nlohmann's copies and Assimp's glTF reader
// (RapidJSON) recurse once per nesting level, so a hostile file of a million nested arrays
// would exhaust the stack. Scene files, glTF files, cache headers and the lighting tool's
// requests are all checked here first.
#pragma once

#include <string>
#include <string_view>

namespace bounce {

/// Deepest nesting any file bounce reads has a use for (a scene nests about 6 levels).
inline constexpr int kMaxJsonDepth = 256;

/// Throws InputError(origin, "LINE:COL") at the first bracket that nests deeper than
/// `max_depth` (brackets inside strings do not count).
void check_json_nesting(std::string_view text, const std::string& origin, int max_depth = kMaxJsonDepth);

}  // namespace bounce
