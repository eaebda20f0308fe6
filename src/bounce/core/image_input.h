// Opening image files to read. OpenImageIO 2.4 aborts the process on some damaged OpenEXR
// headers (a channel of an unknown pixel type), so OpenEXR's core library, whose header checks
// are strict and return errors, parses them first.
#pragma once

#include <OpenImageIO/imageio.h>

#include <memory>
#include <string>

namespace bounce {

/// Opens `path` with OpenImageIO; null, with `error` set to one line saying why, when it is not
/// a regular file, an OpenEXR file's headers are damaged, or OpenImageIO cannot read it.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path, std::string& error);

}  // namespace bounce
