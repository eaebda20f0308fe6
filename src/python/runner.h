// Runs a render off the interpreter's thread, so that Python stays in charge while it works:
// the GIL is released for the render, and the calling thread wakes every 50 ms to hand the
// progress and preview images to the script's callbacks (on the caller's thread, as Blender's
// API requires), to check for Ctrl-C and for a cancel token set elsewhere. A callback that
// raises, or Ctrl-C, cancels the render within a tile; the script then sees that exception.
#pragma once

#include <pybind11/pybind11.h>

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "bounce/core/image.h"
#include "bounce/core/progress.h"

namespace bounce::python {

/// bounce.CancelToken: set from any thread (a UI's button) to stop a render.
struct PyCancel {
    CancelToken token;
};

/// What a render reports while it runs, kept until the calling thread hands it on.
class Monitor : public ProgressSink {
  public:
    Monitor(pybind11::object progress, pybind11::object preview, std::shared_ptr<PyCancel> user_cancel);
    void update(const std::string& name, uint64_t done, uint64_t total, double elapsed) override;
    void finish(const std::string& name, uint64_t total, double elapsed) override;
    /// For RenderRequest::preview: keeps the newest preview image for the calling thread.
    void keep_preview(const Image& image);
    /// The token every pass checks (set by Ctrl-C, a raising callback or the user's token).
    const CancelToken& token() const { return cancel_; }

    /// Runs `work` on a worker thread with the GIL released; the caller's thread polls. Rethrows
    /// work's exception, or the Python exception that cancelled it (KeyboardInterrupt, a
    /// callback's), or bounce.Cancelled for the user's token.
    void run(const std::function<void()>& work);
    /// Same, calling `tick` (without the GIL) before each poll: a render that reports through
    /// something else than this sink (the lighting session) updates it there, and stops when
    /// token() is set.
    void run(const std::function<void()>& work, const std::function<void()>& tick);

  private:
    void poll();  ///< with the GIL: signals, the user's token, callbacks
    void deliver();

    pybind11::object progress_, preview_;
    std::shared_ptr<PyCancel> user_cancel_;
    CancelToken cancel_;
    std::mutex mutex_;
    struct Report {
        std::string name;
        uint64_t done = 0, total = 0;
        double elapsed = 0;
    };
    std::optional<Report> report_;                ///< newest, not yet handed on
    std::shared_ptr<const Image> preview_image_;  ///< newest, not yet handed on
    std::optional<pybind11::error_already_set> raised_;
};

}  // namespace bounce::python
