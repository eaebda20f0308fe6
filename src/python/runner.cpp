#include "runner.h"

#include <chrono>
#include <exception>
#include <future>

#include "image.h"

namespace py = pybind11;

namespace bounce::python {

Monitor::Monitor(py::object progress, py::object preview, std::shared_ptr<PyCancel> user_cancel)
    : progress_(std::move(progress)), preview_(std::move(preview)), user_cancel_(std::move(user_cancel)) {
    cancel = &cancel_;
}

void Monitor::update(const std::string& name, uint64_t done, uint64_t total, double elapsed) {
    std::lock_guard lock(mutex_);
    report_ = Report{name, done, total, elapsed};
}

void Monitor::finish(const std::string& name, uint64_t total, double elapsed) { update(name, total, total, elapsed); }

void Monitor::keep_preview(const Image& image) {
    if (preview_.is_none()) return;
    auto copy = std::make_shared<const Image>(image);
    std::lock_guard lock(mutex_);
    preview_image_ = std::move(copy);
}

void Monitor::deliver() {
    std::optional<Report> report;
    std::shared_ptr<const Image> image;
    {
        std::lock_guard lock(mutex_);
        report.swap(report_);
        image.swap(preview_image_);
    }
    if (report && !progress_.is_none()) progress_(report->name, report->done, report->total, report->elapsed);
    if (image) preview_(wrap_image(std::const_pointer_cast<Image>(image), py::dict()));
}

void Monitor::poll() {
    if (raised_) return;  // cancelled already: wait for the render to stop
    try {
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        deliver();
    } catch (py::error_already_set& e) {
        raised_ = std::move(e);
        cancel_.cancel();
        return;
    }
    if (user_cancel_ && user_cancel_->token.cancelled()) cancel_.cancel();
}

void Monitor::run(const std::function<void()>& work) { run(work, {}); }

void Monitor::run(const std::function<void()>& work, const std::function<void()>& tick) {
    std::exception_ptr failure;
    {
        py::gil_scoped_release release;
        auto done = std::async(std::launch::async, [&] {
            try {
                work();
            } catch (...) {
                failure = std::current_exception();
            }
        });
        while (done.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready) {
            if (tick) tick();
            py::gil_scoped_acquire acquire;
            poll();
        }
    }
    if (raised_) {
        py::error_already_set e = std::move(*raised_);
        raised_.reset();
        throw e;
    }
    if (failure) std::rethrow_exception(failure);
    deliver();  // the last report (100 %) and preview
}

}  // namespace bounce::python
