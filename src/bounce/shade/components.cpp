#include "bounce/shade/components.h"

#include <nlohmann/json.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

namespace bounce {

std::string layer_name_of(const std::string& name) {
    std::string out = name.empty() ? "light" : name;
    for (char& c : out)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
    return out;
}

namespace {

Layer& rgb_layer(Image& image, const std::string& name) { return image.add_layer(name, {name + ".R", name + ".G", name + ".B"}); }

}  // namespace

ComponentLayers::ComponentLayers(Image& image, const Scene& scene, bool on, bool per_light_indirect) : image_(image), on_(on) {
    if (!on_) return;
    emission_ = &rgb_layer(image, "emission");
    diffuse_ = &rgb_layer(image, "diffuse_direct");
    specular_ = &rgb_layer(image, "specular_direct");
    diffuse_ind_ = &rgb_layer(image, "diffuse_indirect");
    specular_ind_ = &rgb_layer(image, "specular_indirect");
    background_ = &rgb_layer(image, "background");
    reflection_ = &rgb_layer(image, "reflection");
    refraction_ = &rgb_layer(image, "refraction");
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        // Two lights of one name keep apart by their index.
        const std::string own = layer_name_of(scene.lights[i].name);
        const bool taken = std::any_of(scene.lights.begin(), scene.lights.begin() + static_cast<std::ptrdiff_t>(i),
                                       [&](const Light& l) { return layer_name_of(l.name) == own; });
        const std::string name = taken ? fmt::format("{}_{}", own, i) : own;
        light_diffuse_.push_back(&rgb_layer(image, "diffuse_direct_" + name));
        light_specular_.push_back(&rgb_layer(image, "specular_direct_" + name));
        if (!per_light_indirect) continue;
        light_diffuse_ind_.push_back(&rgb_layer(image, "diffuse_indirect_" + name));
        light_specular_ind_.push_back(&rgb_layer(image, "specular_indirect_" + name));
    }
    ids_ = &image.add_layer("id", {"id.object", "id.material"});
    nlohmann::json objects = nlohmann::json::array(), materials = nlohmann::json::array();
    for (const Object& o : scene.objects) objects.push_back(o.name);
    for (const Material& m : scene.materials) materials.push_back(m.name);
    image.metadata["object_ids"] = objects.dump();
    image.metadata["material_ids"] = materials.dump();
}

ShadedParts ComponentLayers::parts() const {
    ShadedParts p;
    p.light_diffuse.assign(light_diffuse_.size(), Color(0));
    p.light_specular.assign(light_specular_.size(), Color(0));
    return p;
}

void ComponentLayers::put(Layer* l, int wx, int wy, const Color& c, float weight) {
    float* px = image_.at(*l, wx, wy);
    px[0] += c.x * weight, px[1] += c.y * weight, px[2] += c.z * weight;
}

void ComponentLayers::add(int wx, int wy, const ShadedParts& p, float weight) {
    put(emission_, wx, wy, p.emission, weight);
    put(diffuse_, wx, wy, p.diffuse_direct, weight);
    put(specular_, wx, wy, p.specular_direct, weight);
    for (size_t i = 0; i < light_diffuse_.size() && i < p.light_diffuse.size(); ++i) {
        put(light_diffuse_[i], wx, wy, p.light_diffuse[i], weight);
        put(light_specular_[i], wx, wy, p.light_specular[i], weight);
    }
}

void ComponentLayers::add_indirect(int wx, int wy, const Color& diffuse, const Color& specular, float weight,
                                   std::span<const Color> shares) {
    put(diffuse_ind_, wx, wy, diffuse, weight);
    put(specular_ind_, wx, wy, specular, weight);
    for (size_t i = 0; i < light_diffuse_ind_.size() && i < shares.size(); ++i) {
        put(light_diffuse_ind_[i], wx, wy, diffuse * shares[i], weight);
        put(light_specular_ind_[i], wx, wy, specular * shares[i], weight);
    }
}

void ComponentLayers::background(int wx, int wy, const Color& c) { put(background_, wx, wy, c, 1); }

void ComponentLayers::add_specular(int wx, int wy, bool refraction, const Color& c) {
    put(refraction ? refraction_ : reflection_, wx, wy, c, 1);
}

void ShadedParts::scale(const Color& s) {
    emission *= s, diffuse_direct *= s, specular_direct *= s;
    for (Color& c : light_diffuse) c *= s;
    for (Color& c : light_specular) c *= s;
}

void ComponentLayers::ids(int wx, int wy, uint32_t object, uint32_t material) {
    float* px = image_.at(*ids_, wx, wy);
    px[0] = static_cast<float>(object + 1), px[1] = static_cast<float>(material + 1);
}

}  // namespace bounce
