// Cutout opacity (issue 61): a material's opacity texture read whole into an OpacityMap, which
// every ray's cut (accel/'s filters, the camera's coverage) looks up the same way.
#pragma once

#include <memory>
#include <string>

#include "bounce/scene/scene.h"

namespace bounce {

/// Which channel of an image is opacity: its alpha, or its first channel when it has no alpha
/// (a grey map: MTL's map_d, the scene file's opacity_texture); AlphaOnly: its alpha, none
/// without one (glTF: a base colour texture without alpha is opaque).
enum class OpacityChannel { AlphaOrFirst, AlphaOnly };

/// Reads `path`'s opacity channel into an OpacityMap. Null with `error` set to one line when
/// the file cannot be read, is larger than kMaxWholeTextureTexels (surface_textures.h), or would not fit in memory; null
/// with `error` empty when AlphaOnly finds no alpha channel.
std::shared_ptr<const OpacityMap> load_opacity_map(const std::string& path, OpacityChannel channel, std::string& error);

/// What a material's cutout is, hashed: equal for equal cutouts (mode, opacity, cutoff, the
/// opacity texture's texels), 0 for every opaque material. A BVH part's key and a shot's
/// scene changes judge cutouts by it.
uint64_t cutout_identity(const Material& m);

/// "opaque", "mask", "blend" (the scene file's names) and back.
const char* alpha_mode_name(AlphaMode mode);

}  // namespace bounce
