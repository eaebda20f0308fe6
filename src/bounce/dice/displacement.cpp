#include "bounce/dice/displacement.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "bounce/core/error.h"
#include "bounce/core/image.h"

namespace bounce {

struct DisplacementMap::Impl {
    OIIO::TextureSystem* ts = nullptr;
    OIIO::ustring name;
    ~Impl() {
        if (ts) OIIO::TextureSystem::destroy(ts);
    }
};

DisplacementMap::DisplacementMap(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, "", "displacement map not found (or not a file)");
    // Check it is an image before the texture system (which reports errors only per lookup).
    if (std::string why = texture_problem(path); !why.empty()) throw InputError(path, "", "displacement map: " + why);
    // A private texture system: its cache and errors belong to this map alone.
    impl_->ts = OIIO::TextureSystem::create(false);
    impl_->name = OIIO::ustring(path);
}

DisplacementMap::~DisplacementMap() = default;

float DisplacementMap::height(const Vec2& uv) const {
    OIIO::TextureOpt opt;
    opt.swrap = opt.twrap = OIIO::TextureOpt::WrapPeriodic;
    opt.mipmode = OIIO::TextureOpt::MipModeNoMIP;  // point samples at micropolygon vertices
    opt.interpmode = OIIO::TextureOpt::InterpBilinear;
    float h = 0;
    // OIIO's t runs down the image, uv's v up.
    if (!impl_->ts->texture(impl_->name, opt, uv.x, 1.0f - uv.y, 0, 0, 0, 0, 1, &h))
        throw InputError(path_, "", "cannot read displacement map: " + impl_->ts->geterror());
    if (!std::isfinite(h) || std::fabs(h) > 1e6f)
        throw InputError(path_, fmt::format("near uv ({:.4f}, {:.4f})", uv.x, uv.y),
                         fmt::format("the displacement map holds {} (heights must be finite)", h));
    return h;
}

}  // namespace bounce
