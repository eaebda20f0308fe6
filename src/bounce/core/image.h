// Multi-layer float images and their files: one OpenEXR with `layer.channel` names and
// metadata, and a tone-mapped sRGB PNG for a quick look.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "bounce/core/display.h"
#include "bounce/core/math.h"

namespace bounce {

/// One named group of channels, e.g. "direct" with {"direct.R","direct.G","direct.B"}.
struct Layer {
    std::string name;
    std::vector<std::string> channels;  ///< full EXR channel names
    std::vector<float> data;            ///< interleaved, width*height*channels.size()
};

/// A window (the crop or the full frame) of a full-size image, with layers.
struct Image {
    int full_width = 0, full_height = 0;
    int x0 = 0, y0 = 0, width = 0, height = 0;
    std::deque<Layer> layers;                     ///< deque: add_layer never moves earlier layers
    std::map<std::string, std::string> metadata;  ///< written as "bounce:<key>" attributes

    /// Adds a zero-filled layer; returns it.
    Layer& add_layer(const std::string& name, const std::vector<std::string>& channels);
    const Layer* find(const std::string& name) const;
    Layer* find(const std::string& name);
    float* at(Layer& l, int x, int y) { return &l.data[(static_cast<size_t>(y) * width + x) * l.channels.size()]; }
    const float* at(const Layer& l, int x, int y) const { return &l.data[(static_cast<size_t>(y) * width + x) * l.channels.size()]; }
};

/// An image as bytes for another process of the same build (an MPI exchange), and back.
std::string serialize_image(const Image& image);
Image parse_image(const std::string& bytes);
/// One image of window `w` ({x0, x1, y0, y1}, full-image pixels) from images of its tiles
/// (same layers; each placed by its own x0, y0); pixels no tile covers are 0.
Image assemble_tiles(const std::array<int, 4>& w, const std::vector<Image>& tiles);

/// Writes all layers to one OpenEXR (temporary name, then rename). The layer named "beauty"
/// is written as the unprefixed R,G,B,A channels.
void write_exr(const std::string& path, const Image& image);
/// Reads an EXR written by write_exr (or any EXR: channels grouped by their prefix).
Image read_exr(const std::string& path);
/// Layer `l` of `image` as 8-bit RGB for a screen: colours through `display` after `exposure`
/// stops; directions (N, bentnormal) as 0.5 + 0.5 x; depth as a grey ramp from the nearest
/// (white) to the farthest (dark) surface, pixels that see nothing black; one channel as grey.
std::vector<uint8_t> display_rgb8(const Image& image, const Layer& l, float exposure, const DisplayTransform& display = *srgb_display());
/// Writes layer `layer` as an 8-bit PNG (display_rgb8). InputError(path) if there is no such layer.
void write_png(const std::string& path, const Image& image, const std::string& layer, const DisplayTransform& display);
/// Writes raw 8-bit RGB pixels as a PNG (used for false-colour and diagnostic images).
void write_png_rgb8(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb);

/// Why `path` cannot serve as a texture (through OpenImageIO's texture system): not a readable
/// image, no pixels, or larger than 8192 x 8192 without being tiled and MIP-mapped (the texture
/// system would read and MIP-map it whole, minutes and gigabytes for one lookup: convert it with
/// maketx). Empty when it can.
std::string texture_problem(const std::string& path);

/// Linear to sRGB-encoded value in [0,1].
float srgb_encode(float linear);
/// Linear to the 8-bit sRGB value a PNG stores (clamped to [0, 1] first).
uint8_t srgb8(float linear);

}  // namespace bounce
