// How scene-linear colours become a screen's values: the PNG previews and the lighting tool's
// view go through an OpenColorIO display and view (a studio's config), or through the built-in
// sRGB curve when no config is named. EXRs never do: they stay scene-linear.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace bounce {

/// The config and its display and view. Empty `config`: the OCIO environment variable, else the
/// built-in sRGB curve; empty `display`/`view`: the config's defaults.
struct DisplaySettings {
    std::string config, display, view;
    bool config_given = false;  ///< --ocio-config was on the command line (then it may not be empty)
};

/// A display transform made once (a config is parsed and its processor built) and applied to
/// many pixels from any thread.
class DisplayTransform {
  public:
    /// The built-in sRGB curve (the sRGB piecewise encoding of linear Rec.709 values).
    DisplayTransform();
    /// `settings` resolved against `env_ocio` (the OCIO environment variable's value, or null).
    /// InputError naming the config file and the display or view it lacks, or why it is not a
    /// config; a display or view named without any config is refused as well.
    DisplayTransform(const DisplaySettings& settings, const char* env_ocio);
    ~DisplayTransform();
    DisplayTransform(DisplayTransform&&) noexcept;
    DisplayTransform& operator=(DisplayTransform&&) noexcept;

    /// Scene-linear RGB triples (interleaved, `count` pixels) to display-encoded values in place;
    /// the caller clamps and quantises.
    void apply(float* rgb, size_t count) const;
    /// "sRGB (built-in)" or "<config>: <display> / <view>".
    const std::string& name() const { return name_; }
    bool builtin() const { return !ocio_; }
    /// The config and every file (LUT) its transforms name, as read: inputs no output may overwrite.
    const std::vector<std::string>& files() const { return files_; }

  private:
    struct Ocio;
    std::unique_ptr<const Ocio> ocio_;  ///< null: the built-in curve
    std::string name_ = "sRGB (built-in)";
    std::vector<std::string> files_;
};

/// The built-in sRGB transform, one shared instance (the default of every holder of a transform).
const std::shared_ptr<const DisplayTransform>& srgb_display();

}  // namespace bounce
