#include "bounce/core/image_compare.h"

#include <fmt/format.h>

#include <cmath>

#include "bounce/core/error.h"

namespace bounce {

namespace {

// Accumulates the error of one layer; `test_value(i)` is the test's value at element i of the
// reference layer `rl`.
template <class TestValue>
LayerError layer_error(const std::string& name, const Layer& rl, const Image& test, TestValue test_value, const std::string& test_path,
                       const std::string& ref_path) {
    LayerError e;
    e.layer = name;
    double se = 0, sr = 0, sa = 0, rel = 0;
    size_t n = 0;
    // "A" (coverage) is geometry, not light: leave it out of the beauty error.
    size_t nc = rl.channels.size();
    for (size_t i = 0; i < rl.data.size(); ++i) {
        if (rl.channels[i % nc] == "A") continue;
        double a = test_value(i), b = rl.data[i];
        const size_t pixel = i / nc;
        const auto where = [&] {
            return fmt::format("{} pixel {},{}", rl.name, pixel % static_cast<size_t>(test.width) + test.x0,
                               pixel / static_cast<size_t>(test.width) + test.y0);
        };
        if (!std::isfinite(b)) {
            if (rl.name == "depth") continue;  // the background's depth is infinite
            // A reference that is not finite would score any test as perfect.
            throw InputError(ref_path, where(), "the reference holds a value that is not finite");
        }
        if (!std::isfinite(a)) throw InputError(test_path, where(), "not a finite value where the reference is finite");
        double d = a - b;
        se += d * d;
        sa += std::abs(d);
        sr += std::abs(b);
        rel += d * d / (b * b + 0.01);
        e.max_abs = std::max(e.max_abs, std::abs(d));
        ++n;
    }
    if (n) {
        e.rmse = std::sqrt(se / static_cast<double>(n));
        e.mean_abs = sa / static_cast<double>(n);
        e.mean_ref = sr / static_cast<double>(n);
        e.relmse = rel / static_cast<double>(n);
        // Against an all-zero reference a relative error means nothing: NaN ("n/a").
        e.rel_rmse = e.mean_ref > 0 ? e.rmse / e.mean_ref : std::nan("");
    }
    return e;
}

}  // namespace

std::vector<LayerError> compare_images(const Image& test, const Image& ref, const std::string& layer, const std::string& test_path,
                                       const std::string& ref_path) {
    if (test.width != ref.width || test.height != ref.height || test.x0 != ref.x0 || test.y0 != ref.y0)
        throw InputError(test_path, "",
                         fmt::format("image window {}x{}+{}+{} differs from the reference's {}x{}+{}+{}", test.width, test.height, test.x0,
                                     test.y0, ref.width, ref.height, ref.x0, ref.y0));
    std::vector<LayerError> out;
    for (const Layer& rl : ref.layers) {
        if (!layer.empty() && rl.name != layer) continue;
        const Layer* tl = test.find(rl.name);
        if (!tl) {
            if (!layer.empty()) throw InputError(test_path, "", "no layer \"" + rl.name + "\"");
            continue;
        }
        if (tl->channels != rl.channels) throw InputError(test_path, rl.name, "the layer's channels differ from the reference's");
        out.push_back(layer_error(
            rl.name, rl, test, [&](size_t i) { return double(tl->data[i]); }, test_path, ref_path));
    }
    if (!layer.empty() && layer != kBeautyRefDirect && out.empty())
        throw InputError(test_path, "", "reference has no layer \"" + layer + "\"");
    // The beauty image lit by the reference's direct light: the error a lighter sees from indirect
    // light alone (both renders draw their own direct-light samples, whose noise would hide it).
    const Layer *tb = test.find("beauty"), *td = test.find("direct"), *rb = ref.find("beauty"), *rd = ref.find("direct");
    if ((layer.empty() || layer == kBeautyRefDirect) && tb && td && rb && rd && tb->channels == rb->channels &&
        td->channels == rd->channels && td->channels.size() == 3 && rb->channels.size() >= 3) {
        const size_t nb = rb->channels.size();
        out.push_back(layer_error(
            kBeautyRefDirect, *rb, test,
            [&](size_t i) {
                size_t pixel = i / nb, c = i % nb;
                if (c >= 3) return double(tb->data[i]);
                return double(tb->data[i]) - td->data[pixel * 3 + c] + rd->data[pixel * 3 + c];
            },
            test_path, ref_path));
    } else if (layer == kBeautyRefDirect) {
        throw InputError(test_path, "", "\"" + layer + "\" needs beauty and direct layers in both images");
    }
    return out;
}

std::vector<uint8_t> error_false_colour(const Image& test, const Image& ref, const std::string& layer, double range) {
    const Layer* rl = ref.find(layer);
    const Layer* tl = test.find(layer);
    std::vector<uint8_t> rgb(static_cast<size_t>(ref.width) * ref.height * 3, 0);
    if (!rl || !tl) return rgb;
    size_t nc = std::min<size_t>(3, rl->channels.size()), stride = rl->channels.size();
    for (size_t p = 0; p < static_cast<size_t>(ref.width) * ref.height; ++p) {
        double e = 0;
        for (size_t c = 0; c < nc; ++c) e += std::abs(static_cast<double>(tl->data[p * stride + c]) - rl->data[p * stride + c]);
        double x = std::isfinite(e) ? std::clamp(e / static_cast<double>(nc) / range, 0.0, 1.0) : 1.0;
        // Piecewise ramp: black -> blue -> red -> yellow -> white.
        double r = std::clamp(3 * x - 1, 0.0, 1.0), g = std::clamp(3 * x - 2, 0.0, 1.0);
        double b = x < 1.0 / 3 ? 3 * x : (x < 2.0 / 3 ? 2 - 3 * x : 3 * x - 2);
        rgb[3 * p] = static_cast<uint8_t>(std::lround(255 * r));
        rgb[3 * p + 1] = static_cast<uint8_t>(std::lround(255 * g));
        rgb[3 * p + 2] = static_cast<uint8_t>(std::lround(255 * b));
    }
    return rgb;
}

nlohmann::json layer_errors_json(const std::vector<LayerError>& errors) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& e : errors)
        j[e.layer] = {{"rmse", e.rmse},       {"rel_rmse", std::isnan(e.rel_rmse) ? nlohmann::json() : nlohmann::json(e.rel_rmse)},
                      {"relmse", e.relmse},   {"mean_abs", e.mean_abs},
                      {"max_abs", e.max_abs}, {"mean_ref", e.mean_ref}};
    return j;
}

}  // namespace bounce
