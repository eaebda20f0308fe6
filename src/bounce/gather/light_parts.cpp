#include "bounce/gather/light_parts.h"

namespace bounce {

LightPart combine_parts(const LightParts& parts, std::span<const Color> scales) {
    LightPart out;
    for (size_t i = 0; i < parts.light.size(); ++i) {
        const LightPart& p = parts.light[i];
        const Color& s = scales[i];
        out.E += p.E * s;
        for (size_t c = 0; c < 3; ++c) {
            out.dir[c] += p.dir[c] * s[static_cast<int>(c)];
            out.grad_r[c] += p.grad_r[c] * s[static_cast<int>(c)];
            out.grad_t[c] += p.grad_t[c] * s[static_cast<int>(c)];
        }
    }
    return out;
}

void normalise_shares(std::span<Color> parts) {
    Color sum(0);
    for (const Color& p : parts) sum += p;
    for (Color& p : parts)
        for (int c = 0; c < 3; ++c) p[c] = sum[c] > 0 ? p[c] / sum[c] : 0.0f;
}

}  // namespace bounce
