// The beauty's components as EXR layers for compositing (render.layers = components), named as
// Nuke users know them from other renderers: emission, diffuse_direct, specular_direct (and
// per light: diffuse_direct_<light>, specular_direct_<light>), diffuse_indirect,
// specular_indirect (per light too when the records keep light parts), background, reflection and refraction (what mirrors and glass show),
// and an id layer (id.object, id.material: index + 1, 0 where nothing is seen) whose names are in the header. The parts sum to the beauty.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "bounce/core/image.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// Emission and direct light one fragment sends to the camera, by where it came from.
struct ShadedParts {
    Color emission{0}, diffuse_direct{0}, specular_direct{0};
    std::vector<Color> light_diffuse, light_specular;  ///< per scene light; sized by ComponentLayers::parts
    /// Every part times `s` (a mirror's or glass's base share).
    void scale(const Color& s);
};

/// A light's name as an EXR layer name: letters, digits and '_' (others become '_').
std::string layer_name_of(const std::string& name);

class ComponentLayers {
  public:
    /// With `on`, adds the layers to `image` and the id tables to its metadata
    /// (bounce:object_ids, bounce:material_ids: JSON arrays of names); else does nothing.
    /// `per_light_indirect`: the indirect layers per light as well.
    ComponentLayers(Image& image, const Scene& scene, bool on, bool per_light_indirect = false);
    bool on() const { return on_; }
    /// Zeroed parts sized for this scene's lights.
    ShadedParts parts() const;
    /// Adds `p` x `weight` (emission and direct light) to pixel (wx, wy) of the window.
    void add(int wx, int wy, const ShadedParts& p, float weight);
    /// Adds the indirect light's lobes x `weight`; per light, times each light's `shares`.
    void add_indirect(int wx, int wy, const Color& diffuse, const Color& specular, float weight, std::span<const Color> shares = {});
    void background(int wx, int wy, const Color& c);
    /// Light a mirror's or glass's paths bring (already weighted), by their first bounce.
    void add_specular(int wx, int wy, bool refraction, const Color& c);
    /// The object and material (indices) of the pixel's largest fragment.
    void ids(int wx, int wy, uint32_t object, uint32_t material);

  private:
    void put(Layer* l, int wx, int wy, const Color& c, float weight);
    Image& image_;
    bool on_ = false;
    Layer *emission_ = nullptr, *diffuse_ = nullptr, *specular_ = nullptr, *diffuse_ind_ = nullptr, *specular_ind_ = nullptr,
          *background_ = nullptr, *reflection_ = nullptr, *refraction_ = nullptr, *ids_ = nullptr;
    std::vector<Layer*> light_diffuse_, light_specular_, light_diffuse_ind_, light_specular_ind_;
};

}  // namespace bounce
