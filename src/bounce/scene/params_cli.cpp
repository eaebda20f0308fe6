#include "bounce/scene/params_cli.h"

#include <fmt/format.h>

namespace bounce {

Override flag_override(const Param& p, const std::string& text) {
    const std::string origin = p.flag + " " + text;
    std::string value;
    switch (p.type) {
        case ParamType::Bool:
            value = text;
            break;
        case ParamType::Enum:
        case ParamType::Path:
            value = nlohmann::json(text).dump();
            break;
        case ParamType::Vec3:
        case ParamType::FloatList:
        case ParamType::IntList: {
            // "1,2,3,4", "[1,2,3,4]", "WIDTHxHEIGHT" or "x,y,z": a JSON array of the numbers given.
            std::string list = text;
            if (p.key == "camera.resolution") std::replace(list.begin(), list.end(), 'x', ',');
            value = list.starts_with('[') ? list : "[" + list + "]";
            if (!nlohmann::json::accept(value)) value = nlohmann::json(text).dump();  // check_param names it
            break;
        }
        default:
            value = nlohmann::json::accept(text) ? text : nlohmann::json(text).dump();
            break;
    }
    return Override(p.key + "=" + value, origin);
}

void add_param_flags(CLI::App& app, const ParamTable& table, std::vector<Override>& out) {
    for (const Param& p : table) {
        if (p.flag.empty()) continue;
        std::string help = p.doc;
        if (!p.unit.empty()) help += " [" + p.unit + "]";
        if (p.type == ParamType::Enum) help += fmt::format(" ({})", fmt::join(p.choices, ", "));
        help += fmt::format(" ({}; default {})", p.key, p.default_value().dump());
        if (p.type == ParamType::Bool) {
            const bool sets = p.flag.rfind("--no-", 0) != 0;
            // The doc says what the setting does when on; a --no- flag turns that off.
            if (!sets) help = "turn off: " + help;
            app.add_flag_callback(
                p.flag, [&out, &p, sets] { out.push_back(flag_override(p, sets ? "true" : "false")); }, help);
        } else {
            app.add_option_function<std::string>(
                p.flag, [&out, &p](const std::string& text) { out.push_back(flag_override(p, text)); }, help);
        }
    }
}

}  // namespace bounce
