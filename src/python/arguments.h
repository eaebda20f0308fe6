// The keyword arguments of bounce's Python calls, read by hand: each wrong one is refused with
// one line naming the call and the argument (pybind11's own message for a wrong type is a page
// of overloads), and a keyword no call knows is never dropped in silence.
#pragma once

#include <pybind11/pybind11.h>

#include <optional>
#include <set>
#include <string>

namespace bounce::python {

class Arguments {
  public:
    /// `call` names the call in messages ("render"); positional arguments are refused.
    Arguments(std::string call, const pybind11::args& args, const pybind11::kwargs& kwargs);

    /// A path (str or os.PathLike); "" when not given or None.
    std::string path(const char* name);
    bool flag(const char* name);
    std::string text(const char* name, const std::string& fallback);
    std::optional<double> number(const char* name);
    /// A callable, or None.
    pybind11::object callable(const char* name);
    /// The argument as it was given (None when not given), taken.
    pybind11::object take(const char* name);

    /// The arguments no getter took, by name, in the order given.
    std::vector<std::pair<std::string, pybind11::object>> rest() const;

    /// InputError("python", "call(name=value)", message).
    [[noreturn]] void fail(const std::string& name, pybind11::handle value, const std::string& message) const;
    const std::string& call() const { return call_; }

  private:
    std::string call_;
    pybind11::dict given_;
    std::set<std::string> taken_;
};

}  // namespace bounce::python
