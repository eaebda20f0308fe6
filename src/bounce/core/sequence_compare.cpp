#include "bounce/core/sequence_compare.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "bounce/core/error.h"
#include "bounce/core/image_compare.h"

namespace bounce {

namespace {

const Layer& layer_of(const Image& img, const std::string& layer, const std::string& name) {
    const Layer* l = img.find(layer);
    if (!l) throw InputError(name, "", "no layer \"" + layer + "\"");
    return *l;
}

}  // namespace

SequenceError compare_sequences(const std::function<Image(int)>& test, const std::function<Image(int)>& ref, int first, int last,
                                const std::string& layer, const std::function<std::string(int)>& name) {
    SequenceError out;
    Image prev_a, prev_b;
    double sum_sq = 0, sum_ref = 0;
    size_t n_pairs = 0, n_ref = 0;
    std::vector<float> temporal;  // per pixel and frame pair
    for (int t = first; t <= last; ++t) {
        Image a = test(t), b = ref(t);
        const std::vector<LayerError> e = compare_images(a, b, layer, name(t));
        out.frames.push_back(t);
        out.rel_rmse.push_back(e.empty() ? 0 : e[0].rel_rmse);
        const Layer &la = layer_of(a, layer, name(t)), &lb = layer_of(b, layer, "reference");
        const size_t nc = la.channels.size();
        for (float v : lb.data) sum_ref += std::abs(v), ++n_ref;
        if (t > first) {
            const Layer &pa = layer_of(prev_a, layer, name(t - 1)), &pb = layer_of(prev_b, layer, "reference");
            if (pa.data.size() != la.data.size())
                throw InputError(name(t), "", fmt::format("frame {} has another size than frame {}", t, t - 1));
            for (size_t p = 0; p < la.data.size() / nc; ++p) {
                double pixel = 0;
                for (size_t c = 0; c < nc; ++c) {
                    const size_t i = p * nc + c;
                    const double d = (static_cast<double>(la.data[i]) - pa.data[i]) - (static_cast<double>(lb.data[i]) - pb.data[i]);
                    sum_sq += d * d;
                    pixel += std::abs(d);
                    ++n_pairs;
                }
                temporal.push_back(static_cast<float>(pixel / static_cast<double>(nc)));
            }
        }
        prev_a = std::move(a), prev_b = std::move(b);
    }
    for (double e : out.rel_rmse) out.mean_rel_rmse += e / static_cast<double>(out.rel_rmse.size());
    const double mean_ref = n_ref ? sum_ref / static_cast<double>(n_ref) : 0;
    if (n_pairs > 0 && mean_ref > 0) {
        out.flicker = std::sqrt(sum_sq / static_cast<double>(n_pairs)) / mean_ref;
        const size_t k = std::min(temporal.size() - 1, static_cast<size_t>(0.999 * static_cast<double>(temporal.size())));
        std::nth_element(temporal.begin(), temporal.begin() + static_cast<std::ptrdiff_t>(k), temporal.end());
        out.popping = temporal[k] / mean_ref;
    }
    return out;
}

std::vector<uint8_t> sequence_strip(const std::function<Image(int)>& frames, int first, int last, const std::string& layer, int tiles,
                                    int& width, int& height) {
    const int count = std::max(1, std::min(tiles, last - first + 1));
    std::vector<int> picked;
    for (int i = 0; i < count; ++i)
        picked.push_back(count == 1 ? first : first + static_cast<int>(std::lround(static_cast<double>(i) * (last - first) / (count - 1))));
    std::vector<std::vector<uint8_t>> rows[2];
    int w = 0, h = 0;
    bool dots = true;
    for (int t : picked) {
        const Image img = frames(t);
        w = img.width, h = img.height;
        rows[0].push_back(display_rgb8(img, layer_of(img, layer, fmt::format("frame {}", t)), 0));
        const Layer* rec = img.find("records");
        dots = dots && rec;
        if (rec) rows[1].push_back(display_rgb8(img, *rec, 0));
    }
    const int nrows = dots ? 2 : 1;
    width = w * count, height = h * nrows;
    std::vector<uint8_t> out(static_cast<size_t>(width) * height * 3, 0);
    for (int r = 0; r < nrows; ++r)
        for (int i = 0; i < count; ++i)
            for (int y = 0; y < h; ++y)
                std::copy_n(&rows[r][static_cast<size_t>(i)][static_cast<size_t>(y) * w * 3], static_cast<size_t>(w) * 3,
                            &out[(static_cast<size_t>(r * h + y) * width + static_cast<size_t>(i * w)) * 3]);
    return out;
}

}  // namespace bounce
