// Readers of the lighter's per-object controls: which rays see an object ("visible_to"),
// holdouts ("matte"), and which objects a light lights and which cast its shadows
// ("light_link", "shadow_link": object names or globs). docs/scene-format.md.
#pragma once

#include "bounce/scene/json_reader.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// An object's "visible_to" {camera, shadows, indirect, reflections} and "matte".
void read_object_visibility(const JsonReader& r, Object& obj);
/// A "visible_to" object (an object's or a fur block's) over the defaults in `to`.
void read_visibility(const JsonReader& r, RayVisibility& to);

/// A light's "light_link" and "shadow_link" ({"include": [...]} or {"exclude": [...]}),
/// resolved against the names of `scene.objects`; a pattern that matches no object is an
/// error. A shadow link takes the next free ray-mask slot (`shadow_slots` counts them).
void read_light_links(const JsonReader& r, const Scene& scene, Light& light, int& shadow_slots);

}  // namespace bounce
