#include "bounce/dice/displacement.h"

#include <OpenImageIO/imageio.h>
#include <OpenImageIO/texture.h>

#include <filesystem>

#include "bounce/core/error.h"

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
    {  // Check it is an image before the texture system (which reports errors only per lookup).
        auto in = OIIO::ImageInput::open(path);
        if (!in) throw InputError(path, "", "cannot read displacement map: " + OIIO::geterror());
        if (in->spec().width <= 0 || in->spec().height <= 0) throw InputError(path, "", "displacement map has no pixels");
    }
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
    return h;
}

}  // namespace bounce
