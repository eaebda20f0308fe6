#include "bounce/scene/link_reader.h"

#include <fmt/format.h>
#include <fnmatch.h>

namespace bounce {

using nlohmann::json;

void read_object_visibility(const JsonReader& r, Object& obj) {
    obj.matte = r.boolean("matte", obj.matte);
    read_visibility(r, obj.visible_to);
}

void read_visibility(const JsonReader& r, RayVisibility& to) {
    if (!r.has("visible_to")) return;
    if (!r.raw("visible_to").is_object())
        r.fail("visible_to", "expected an object {\"camera\", \"shadows\", \"indirect\", \"reflections\"}");
    JsonReader v(r.raw("visible_to"), r.at("visible_to"), r.ctx(), {"camera", "shadows", "indirect", "reflections"});
    to.camera = v.boolean("camera", to.camera);
    to.shadows = v.boolean("shadows", to.shadows);
    to.indirect = v.boolean("indirect", to.indirect);
    to.reflections = v.boolean("reflections", to.reflections);
}

namespace {

/// {"include": [patterns]} or {"exclude": [patterns]} as one flag per object.
std::vector<uint8_t> read_link(const JsonReader& r, const std::string& key, const Scene& scene) {
    const json& link = r.raw(key);
    if (!link.is_object() || link.size() != 1 || !(link.contains("include") || link.contains("exclude")))
        r.fail(key, "expected {\"include\": [names]} or {\"exclude\": [names]} (object names; * ? [..] globs)");
    JsonReader l(link, r.at(key), r.ctx(), {"include", "exclude"});
    const bool include = link.contains("include");
    const std::string list = include ? "include" : "exclude";
    const json& patterns = link.at(list);
    if (!patterns.is_array()) l.fail(list, "expected an array of object names or globs");
    std::vector<uint8_t> flags(scene.objects.size(), include ? 0 : 1);
    for (size_t i = 0; i < patterns.size(); ++i) {
        const std::string at = l.at(list) + fmt::format("/{}", i);
        if (!patterns[i].is_string() || patterns[i].get<std::string>().empty())
            r.ctx().fail(at, fmt::format("expected an object name or glob, got {}", json_type_name(patterns[i])));
        const std::string pattern = patterns[i].get<std::string>();
        bool matched = false;
        for (size_t o = 0; o < scene.objects.size(); ++o)
            if (fnmatch(pattern.c_str(), scene.objects[o].name.c_str(), 0) == 0) flags[o] = include ? 1 : 0, matched = true;
        // A typo would silently link nothing.
        if (!matched) r.ctx().fail(at, fmt::format("\"{}\" matches no object's name", pattern));
    }
    return flags;
}

}  // namespace

void read_light_links(const JsonReader& r, const Scene& scene, Light& light, int& shadow_slots) {
    if (r.has("light_link")) light.lit = read_link(r, "light_link", scene);
    if (!r.has("shadow_link")) return;
    light.shadowed_by = read_link(r, "shadow_link", scene);
    if (shadow_slots >= kMaxShadowLinkedLights)
        r.fail("shadow_link", fmt::format("at most {} lights may have a shadow link", kMaxShadowLinkedLights));
    light.shadow_slot = shadow_slots++;
}

}  // namespace bounce
