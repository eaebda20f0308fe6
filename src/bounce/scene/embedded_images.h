// Images a mesh file carries inside it (a .glb's buffer views, a glTF's data: URIs): Assimp hands
// them over as bytes, and textures are files (OpenImageIO's texture cache, the mesh cache's
// checks), so each is written once, named by its content, to a folder of the user's cache.
#pragma once

#include <string>

struct aiTexture;

namespace bounce {

/// The folder embedded images are written to: $BOUNCE_IMAGE_CACHE, else
/// $XDG_CACHE_HOME/bounce/images, else ~/.cache/bounce/images, else /tmp/bounce-images-<uid>.
std::string embedded_image_folder();

/// Whether `file` is one embedded_image_file wrote (in embedded_image_folder()).
bool is_embedded_image(const std::string& file);

/// The file holding `texture`'s bytes (written there atomically unless it is already there).
/// Throws InputError naming `path` and `where` when the image is not an encoded file (raw texels)
/// or the folder cannot take it.
std::string embedded_image_file(const aiTexture& texture, const std::string& path, const std::string& where);

}  // namespace bounce
