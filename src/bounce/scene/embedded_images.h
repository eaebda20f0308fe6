// Images a mesh file carries inside it (a .glb's buffer views, a glTF's data: URIs): Assimp hands
// them over as bytes, and textures are files (OpenImageIO's texture cache, the mesh cache's
// checks), so each is written once, named by its content, to a folder of the user's cache.
#pragma once

#include <string>

struct aiTexture;

namespace bounce {

/// Whether `file` is one embedded_image_file wrote into `folder` (LoadResources::images).
bool is_embedded_image(const std::string& file, const std::string& folder);

/// The file of `folder` holding `texture`'s bytes (written there atomically unless it is already
/// there). Throws InputError naming `path` and `where` when the image is not an encoded file (raw
/// texels), no folder is given or the folder cannot take it.
std::string embedded_image_file(const aiTexture& texture, const std::string& folder, const std::string& path, const std::string& where);

}  // namespace bounce
