// Textures a material reads whole at load (issue 61): its emission (so that light sampling,
// gathers and the camera see the same radiance) beside its opacity (opacity.h); and the uv
// transform every texture of a material is read through (glTF's KHR_texture_transform).
#pragma once

#include <memory>
#include <string>

#include "bounce/scene/scene.h"

#include <OpenImageIO/imageio.h>

namespace bounce {

/// The largest texture read whole (opacity: 2 bytes a texel; emission: 12).
inline constexpr double kMaxWholeTextureTexels = 8192.0 * 8192.0;

/// `path` opened to be read whole as a `kind` ("opacity", "emission") texture: null with one
/// line in `error` when it cannot be read, has no pixels or more than kMaxWholeTextureTexels.
std::unique_ptr<OIIO::ImageInput> open_whole_texture(const std::string& path, const char* kind, std::string& error);

/// Reads `path`'s first three channels (a grey image's one three times) as linear radiance
/// factors. Null with `error` set to one line when the file cannot be read, is larger than
/// kMaxWholeTextureTexels, would not fit in memory, or holds a texel that is not a number in
/// [0, kMaxRadiometric] (naming it).
std::shared_ptr<const EmissionMap> load_emission_map(const std::string& path, std::string& error);

/// A uv transform from KHR_texture_transform's (or the scene file's) values: one line in `error`
/// when one is not finite, beyond 1e6, or a scale is 0 (every texel would collapse to one).
bool make_uv_transform(const Vec2& offset, float rotation, const Vec2& scale, UvTransform& out, std::string& error);

}  // namespace bounce
