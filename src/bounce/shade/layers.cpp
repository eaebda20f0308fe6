#include "bounce/shade/layers.h"

#include <cmath>

#include "bounce/deep/deep_buffer.h"

namespace bounce {

void add_records_layer(Image& image, const Camera& camera, const std::vector<Vec3>& positions) {
    const Layer* beauty = image.find("beauty");
    Layer& l = image.add_layer("records", {"records.R", "records.G", "records.B"});
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c) image.at(l, x, y)[c] = 0.5f * std::min(1.0f, image.at(*beauty, x, y)[c]);
    CameraRays rays(camera);
    for (const Vec3& p : positions) {
        float px, py;
        if (!rays.project(p, px, py)) continue;
        int cx = static_cast<int>(std::floor(px)) - image.x0, cy = static_cast<int>(std::floor(py)) - image.y0;
        for (int y = cy - 1; y <= cy + 1; ++y)
            for (int x = cx - 1; x <= cx + 1; ++x)
                if (x >= 0 && y >= 0 && x < image.width && y < image.height)
                    for (int c = 0; c < 3; ++c) image.at(l, x, y)[c] = 1.0f;
    }
}

void add_fragment_mask_layer(Image& image, const DeepBuffer& deep, const std::vector<uint8_t>& flags, const std::string& name) {
    Layer& l = image.add_layer(name, {name + ".Y"});
    for (int y = 0; y < deep.height; ++y)
        for (int x = 0; x < deep.width; ++x) {
            size_t first = deep.offsets[static_cast<size_t>(y) * deep.width + x];
            float cover = 0;
            auto frags = deep.pixel(x, y);
            for (size_t k = 0; k < frags.size(); ++k)
                if (flags[first + k]) cover += frags[k].weight;
            *image.at(l, x, y) = cover;
        }
}

}  // namespace bounce
