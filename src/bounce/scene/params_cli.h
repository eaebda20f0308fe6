// The command-line flags of the parameter table (CLI11): one flag per row that names one, its
// help from the row's doc, unit and default; the values become overrides validated exactly as
// scene-file values are, and errors name the flag as the user wrote it.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "bounce/scene/json_reader.h"
#include "bounce/config/params.h"

namespace bounce {

/// The override a flag's text stands for ("--crop 1,2,3,4" -> render.crop=[1,2,3,4]).
Override flag_override(const Param& p, const std::string& text);

/// Adds the table's flags to `app`; after parsing, `out` holds one override per flag given,
/// in table order.
void add_param_flags(CLI::App& app, const ParamTable& table, std::vector<Override>& out);

}  // namespace bounce
