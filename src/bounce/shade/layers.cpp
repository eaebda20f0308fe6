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

std::vector<float> fragment_mask(const DeepBuffer& deep, const std::vector<uint8_t>& flags) {
    std::vector<float> mask(deep.pixel_count(), 0.0f);
    for (int y = 0; y < deep.height; ++y)
        for (int x = 0; x < deep.width; ++x) {
            const size_t first = deep.offsets[static_cast<size_t>(y) * deep.width + x];
            auto frags = deep.pixel(x, y);
            float cover = 0;
            for (size_t k = 0; k < frags.size(); ++k)
                if (flags[first + k]) cover += frags[k].weight;
            mask[static_cast<size_t>(y) * deep.width + x] = cover;
        }
    return mask;
}

void add_mask_layer(Image& image, const std::vector<float>& mask, const std::string& name) {
    Layer& l = image.add_layer(name, {name + ".Y"});
    std::copy(mask.begin(), mask.end(), l.data.begin());
}

}  // namespace bounce
