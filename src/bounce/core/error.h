// Errors about the user's input: they name the file and the place (line:col or JSON pointer)
// and make the CLI exit with status 2. Anything else that escapes is a bug.
#pragma once

#include <stdexcept>
#include <initializer_list>
#include <string>
#include <vector>

namespace bounce {

class InputError : public std::runtime_error {
  public:
    /// `file`: the offending file (or "command line"); `place`: "12:5", "/lights/0/intensity",
    /// "--res" or empty.
    InputError(std::string file, std::string place, const std::string& message)
        : std::runtime_error(format(file, place, message)), file_(std::move(file)), place_(std::move(place)) {}
    const std::string& file() const { return file_; }
    const std::string& place() const { return place_; }

  private:
    static std::string format(const std::string& file, const std::string& place, const std::string& message) {
        std::string s = file;
        if (!place.empty()) s += ": " + place;
        if (!s.empty()) s += ": ";
        s += "error: " + message;
        // One line, always: library messages (OpenImageIO, Assimp) may carry newlines.
        for (char& c : s)
            if (c == '\n' || c == '\r') c = ' ';
        while (!s.empty() && s.back() == ' ') s.pop_back();
        return s;
    }
    std::string file_, place_;
};

/// Levenshtein-nearest candidate for "did you mean" hints; empty if none is close.
std::string closest_match(const std::string& word, const std::initializer_list<std::string>& options);
std::string closest_match(const std::string& word, const std::vector<std::string>& options);

}  // namespace bounce
