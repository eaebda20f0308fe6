// Error between two renders, per layer: what `bounce compare` prints and the benchmarks use.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bounce/core/image.h"

namespace bounce {

struct LayerError {
    std::string layer;
    double rmse = 0;      ///< sqrt(mean((a - b)^2)) over pixels and channels
    double rel_rmse = 0;  ///< rmse / mean(|b|): the project's "relative RMSE"
    double relmse = 0;    ///< mean((a - b)^2 / (b^2 + 0.01)) (rendering-literature relMSE)
    double mean_abs = 0;  ///< mean |a - b|
    double max_abs = 0;   ///< max |a - b|
    double mean_ref = 0;  ///< mean(b)
};

/// The derived layer comparing the test's beauty with its direct light replaced by the
/// reference's (beauty − direct + reference direct): the beauty error that indirect light causes.
inline constexpr const char* kBeautyRefDirect = "beauty_ref_direct";

/// Compares `test` against `reference`, layer by layer (only `layer` if non-empty), plus
/// kBeautyRefDirect when both images have beauty and direct layers. Both must
/// cover the same window. Throws InputError (naming `test_path`) on mismatched sizes or a
/// missing layer, and naming `ref_path` where the reference is not finite (the depth layer's
/// background aside).
std::vector<LayerError> compare_images(const Image& test, const Image& reference, const std::string& layer, const std::string& test_path,
                                       const std::string& ref_path = "reference");

/// {layer: {rmse, rel_rmse (null where the reference's mean is 0), relmse, mean_abs, max_abs,
/// mean_ref}}: what `bounce compare --json` prints.
nlohmann::json layer_errors_json(const std::vector<LayerError>& errors);

/// False-colour map of the per-pixel error of `layer` (mean over channels of |a - b|), black
/// at 0 through blue, red and yellow to white at `range`.
std::vector<uint8_t> error_false_colour(const Image& test, const Image& reference, const std::string& layer, double range);

}  // namespace bounce
