#include "bounce/core/display.h"

#include <OpenColorIO/OpenColorIO.h>
#include <fmt/format.h>

#include <memory>
#include <vector>

#include "bounce/core/error.h"
#include "bounce/core/files.h"
#include "bounce/core/image.h"

namespace OCIO = OCIO_NAMESPACE;

namespace bounce {

struct DisplayTransform::Ocio {
    OCIO::ConstCPUProcessorRcPtr cpu;
};

namespace {

std::vector<std::string> names(int count, const auto& name_at) {
    std::vector<std::string> out;
    for (int i = 0; i < count; ++i) out.emplace_back(name_at(i));
    return out;
}

/// `wanted` if the config lists it, its default when `wanted` is empty; InputError otherwise.
std::string pick(const std::string& config, const std::string& what, const std::string& wanted, const char* fallback,
                 const std::vector<std::string>& listed) {
    if (wanted.empty()) {
        if (!fallback || !*fallback) throw InputError(config, what, "the config has no default " + what);
        return fallback;
    }
    for (const std::string& n : listed)
        if (n == wanted) return wanted;
    throw InputError(config, what, fmt::format("no {} '{}'; the config has: {}", what, wanted, fmt::join(listed, ", ")));
}

void file_transforms(const OCIO::ConstTransformRcPtr& t, std::vector<std::string>& out) {
    if (!t) return;
    if (const auto f = OCIO::DynamicPtrCast<const OCIO::FileTransform>(t)) {
        if (f->getSrc() && *f->getSrc()) out.emplace_back(f->getSrc());
    } else if (const auto g = OCIO::DynamicPtrCast<const OCIO::GroupTransform>(t)) {
        for (int i = 0; i < g->getNumTransforms(); ++i) file_transforms(g->getTransform(i), out);
    }
}

/// Every file the config's transforms name (colour spaces, looks, view and named transforms),
/// resolved through its search path: the LUTs it may read. Files it cannot find are left out
/// (OpenColorIO refuses them if the view uses them); one that is not a regular file (a FIFO
/// would block OpenColorIO's open() for good) is refused here, before OpenColorIO opens it.
std::vector<std::string> config_files(const OCIO::ConstConfigRcPtr& c, const std::string& config) {
    std::vector<std::string> named;
    for (int i = 0; i < c->getNumColorSpaces(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL); ++i) {
        const auto cs = c->getColorSpace(c->getColorSpaceNameByIndex(OCIO::SEARCH_REFERENCE_SPACE_ALL, OCIO::COLORSPACE_ALL, i));
        if (!cs) continue;
        file_transforms(cs->getTransform(OCIO::COLORSPACE_DIR_TO_REFERENCE), named);
        file_transforms(cs->getTransform(OCIO::COLORSPACE_DIR_FROM_REFERENCE), named);
    }
    for (int i = 0; i < c->getNumLooks(); ++i)
        if (const auto look = c->getLook(c->getLookNameByIndex(i))) {
            file_transforms(look->getTransform(), named);
            file_transforms(look->getInverseTransform(), named);
        }
    for (int i = 0; i < c->getNumViewTransforms(); ++i)
        if (const auto v = c->getViewTransform(c->getViewTransformNameByIndex(i))) {
            file_transforms(v->getTransform(OCIO::VIEWTRANSFORM_DIR_TO_REFERENCE), named);
            file_transforms(v->getTransform(OCIO::VIEWTRANSFORM_DIR_FROM_REFERENCE), named);
        }
    for (int i = 0; i < c->getNumNamedTransforms(); ++i)
        if (const auto n = c->getNamedTransform(c->getNamedTransformNameByIndex(i))) {
            file_transforms(n->getTransform(OCIO::TRANSFORM_DIR_FORWARD), named);
            file_transforms(n->getTransform(OCIO::TRANSFORM_DIR_INVERSE), named);
        }
    std::vector<std::string> out;
    const OCIO::ConstContextRcPtr context = c->getCurrentContext();
    for (const std::string& src : named) {
        std::string path;
        try {
            path = context->resolveFileLocation(src.c_str());
        } catch (const OCIO::Exception&) {
            continue;
        }
        try {
            check_input_file(path);
        } catch (const InputError& e) {
            throw InputError(config, "FileTransform " + src, e.what());
        }
        out.push_back(path);
    }
    return out;
}

}  // namespace

DisplayTransform::DisplayTransform() = default;
DisplayTransform::~DisplayTransform() = default;
DisplayTransform::DisplayTransform(DisplayTransform&&) noexcept = default;
DisplayTransform& DisplayTransform::operator=(DisplayTransform&&) noexcept = default;

DisplayTransform::DisplayTransform(const DisplaySettings& s, const char* env_ocio) {
    // An empty --ocio-config is a mistake, not "none" ($OCIO empty means unset, as OpenColorIO reads it).
    if (s.config_given && s.config.empty())
        throw InputError("command line", "--ocio-config ''", "an empty file name (leave the option out for $OCIO or the built-in sRGB)");
    const std::string config = !s.config.empty() ? s.config : env_ocio ? env_ocio : "";
    if (config.empty()) {
        if (!s.display.empty() || !s.view.empty())
            throw InputError("command line", s.display.empty() ? "--view" : "--display",
                             "names a display or view of an OpenColorIO config, but neither --ocio-config nor OCIO names one");
        return;
    }
    check_input_file(config);
    try {
        const OCIO::ConstConfigRcPtr c = OCIO::Config::CreateFromFile(config.c_str());
        files_ = config_files(c, config);
        files_.insert(files_.begin(), config);
        const std::string display =
            pick(config, "display", s.display, c->getDefaultDisplay(), names(c->getNumDisplays(), [&](int i) { return c->getDisplay(i); }));
        const std::string view = pick(config, "view", s.view, c->getDefaultView(display.c_str()),
                                      names(c->getNumViews(display.c_str()), [&](int i) { return c->getView(display.c_str(), i); }));
        const OCIO::DisplayViewTransformRcPtr t = OCIO::DisplayViewTransform::Create();
        t->setSrc(OCIO::ROLE_SCENE_LINEAR);
        t->setDisplay(display.c_str());
        t->setView(view.c_str());
        ocio_ = std::make_unique<const Ocio>(Ocio{c->getProcessor(t)->getDefaultCPUProcessor()});
        name_ = fmt::format("{}: {} / {}", config, display, view);
    } catch (const OCIO::Exception& e) {
        throw InputError(config, "", fmt::format("not a usable OpenColorIO config: {}", e.what()));
    }
}

const std::shared_ptr<const DisplayTransform>& srgb_display() {
    static const auto builtin = std::make_shared<const DisplayTransform>();
    return builtin;
}

void DisplayTransform::apply(float* rgb, size_t count) const {
    if (!ocio_) {
        for (size_t i = 0; i < 3 * count; ++i) rgb[i] = srgb_encode(rgb[i]);
        return;
    }
    OCIO::PackedImageDesc desc(rgb, static_cast<long>(count), 1, 3);
    ocio_->cpu->apply(desc);
}

}  // namespace bounce
