// PLY files before Assimp reads them (mesh_checks.h): the header's elements against the
// body. A binary body must be long enough for what the header declares; an ASCII body is read
// line by line against it, since Assimp's ASCII reader takes a vertex line for a face (and then
// aborts in its triangulation) or a list count of 255 with three indices.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <iterator>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "bounce/core/files.h"
#include "bounce/core/error.h"
#include "bounce/scene/mesh_checks.h"

namespace bounce {

namespace {

/// A PLY scalar type, decoded once from the header (the body's values are many).
enum class Scalar : uint8_t { None, I8, U8, I16, U16, I32, U32, F32, F64 };

Scalar scalar_of(const std::string& t) {
    static const std::map<std::string, Scalar> kinds = {
        {"char", Scalar::I8},   {"int8", Scalar::I8},     {"uchar", Scalar::U8},   {"uint8", Scalar::U8},
        {"short", Scalar::I16}, {"int16", Scalar::I16},   {"ushort", Scalar::U16}, {"uint16", Scalar::U16},
        {"int", Scalar::I32},   {"int32", Scalar::I32},   {"uint", Scalar::U32},   {"uint32", Scalar::U32},
        {"float", Scalar::F32}, {"float32", Scalar::F32}, {"double", Scalar::F64}, {"float64", Scalar::F64}};
    auto it = kinds.find(t);
    return it == kinds.end() ? Scalar::None : it->second;
}

/// Bytes of one value (0 for None).
uint64_t size_of(Scalar s) {
    switch (s) {
        case Scalar::I8:
        case Scalar::U8:
            return 1;
        case Scalar::I16:
        case Scalar::U16:
            return 2;
        case Scalar::I32:
        case Scalar::U32:
        case Scalar::F32:
            return 4;
        case Scalar::F64:
            return 8;
        case Scalar::None:
            break;
    }
    return 0;
}

bool is_integer(Scalar s) { return s != Scalar::F32 && s != Scalar::F64; }

struct PlyProperty {
    std::string name, type_name;  ///< a list's item type, as the header names it
    Scalar type = Scalar::None;   ///< a list's item type
    Scalar count = Scalar::None;  ///< a list's count type (None: a scalar)
};
struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};
/// A face's list holds vertex indices (checked against the vertex count).
bool indexes_vertices(const PlyElement& e, const PlyProperty& p) { return e.name == "face" && p.count != Scalar::None; }
/// Most values one ASCII list may hold (a polygon's corners).
constexpr uint64_t kMaxListCount = 1u << 16;

/// One ASCII value of type `type`; false when it is not a number of that type.
bool read_value(const std::string& token, Scalar type, double& out) {
    errno = 0;
    char* end = nullptr;
    out = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(out)) return false;
    return !is_integer(type) || out == std::floor(out);
}

/// No control bytes but tabs and a line's carriage return.
bool is_text(const std::string& line) {
    return std::none_of(line.begin(), line.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\r'; });
}

/// The ASCII body, element by element, line by line (blank lines skipped).
void check_ascii_body(std::istream& in, const std::string& path, size_t line_no, const std::vector<PlyElement>& elements,
                      uint64_t vertices) {
    std::string line;
    for (const PlyElement& e : elements)
        for (uint64_t i = 0; i < e.count; ++i) {
            do {
                if (!std::getline(in, line))
                    throw InputError(path, fmt::format("line {}", line_no + 1),
                                     fmt::format("the header declares {} {} elements; the file ends at {} {}", e.count, e.name, e.name, i));
                ++line_no;
            } while (line.find_first_not_of(" \t\r") == std::string::npos);
            // Text only: Assimp's tokens end at a NUL where ours would not (the mesh fuzzer).
            if (!is_text(line)) throw InputError(path, fmt::format("line {}", line_no), "the body holds a byte that is not text");
            std::istringstream ls(line);
            std::vector<std::string> tokens;
            for (std::string t; ls >> t;) tokens.push_back(t);
            const std::string where = fmt::format("line {}", line_no);
            const std::string what = fmt::format("{} {}", e.name, i);
            size_t at = 0;
            for (const PlyProperty& p : e.properties) {
                double v = 0;
                uint64_t n = 1;
                if (p.count != Scalar::None) {
                    if (at >= tokens.size() || !read_value(tokens[at], p.count, v) || v < 0 || v > static_cast<double>(kMaxListCount))
                        throw InputError(path, where,
                                         fmt::format("{}: '{}' is not a list count of {} (0 to {})", what,
                                                     at < tokens.size() ? tokens[at] : "", p.name, kMaxListCount));
                    n = static_cast<uint64_t>(v), ++at;
                }
                for (uint64_t k = 0; k < n; ++k, ++at) {
                    if (at >= tokens.size())
                        throw InputError(path, where, fmt::format("{}: {} values, fewer than its properties need", what, tokens.size()));
                    if (!read_value(tokens[at], p.type, v))
                        throw InputError(path, where, fmt::format("{}: '{}' is not a {} ({})", what, tokens[at], p.type_name, p.name));
                    if (indexes_vertices(e, p) && (v < 0 || v >= static_cast<double>(vertices)))
                        throw InputError(path, where,
                                         fmt::format("{}: vertex index {} outside the {} vertices", what, tokens[at], vertices));
                }
            }
            if (at != tokens.size())
                throw InputError(path, where, fmt::format("{}: {} values where its properties take {}", what, tokens.size(), at));
        }
    while (std::getline(in, line)) {
        ++line_no;
        if (line.find_first_not_of(" \t\r") != std::string::npos)
            throw InputError(path, fmt::format("line {}", line_no), "data past the elements the header declares");
    }
}

/// A binary value of `type` at `p` as a double (`swap`: the file's byte order is not this machine's).
double binary_value(const char* p, Scalar type, bool swap) {
    char b[8];
    const uint64_t n = size_of(type);
    for (uint64_t i = 0; i < n; ++i) b[i] = p[swap ? n - 1 - i : i];
    const auto as = [&b]<typename T>(T) {
        T v;
        std::memcpy(&v, b, sizeof(T));
        return static_cast<double>(v);
    };
    switch (type) {
        case Scalar::I8:
            return as(int8_t{});
        case Scalar::U8:
            return as(uint8_t{});
        case Scalar::I16:
            return as(int16_t{});
        case Scalar::U16:
            return as(uint16_t{});
        case Scalar::I32:
            return as(int32_t{});
        case Scalar::U32:
            return as(uint32_t{});
        case Scalar::F32:
            return as(float{});
        case Scalar::F64:
        case Scalar::None:
            break;
    }
    return as(double{});
}

/// A binary body, element by element: every list count within bounds and the file, every face
/// index within the vertices (a uint count of 0xFFFFFFFF ended in std::bad_alloc in Assimp).
void check_binary_body(const std::string& body, const std::string& path, const std::vector<PlyElement>& elements, uint64_t vertices,
                       bool swap) {
    uint64_t at = 0;
    const auto need = [&](uint64_t n, const PlyElement& e, uint64_t i) {
        if (n > body.size() - at)
            throw InputError(path, fmt::format("byte {} of the body", at), fmt::format("the file ends inside {} {}", e.name, i));
    };
    for (const PlyElement& e : elements)
        for (uint64_t i = 0; i < e.count; ++i)
            for (const PlyProperty& p : e.properties) {
                if (p.count == Scalar::None) {
                    need(size_of(p.type), e, i), at += size_of(p.type);
                    continue;
                }
                need(size_of(p.count), e, i);
                const double n = binary_value(body.data() + at, p.count, swap);
                if (!(n >= 0 && n <= static_cast<double>(kMaxListCount)))
                    throw InputError(path, fmt::format("byte {} of the body", at),
                                     fmt::format("{} {}: a list of {:g} {} (at most {})", e.name, i, n, p.name, kMaxListCount));
                at += size_of(p.count);
                const uint64_t size = size_of(p.type), count = static_cast<uint64_t>(n);
                need(count * size, e, i);
                for (uint64_t k = 0; indexes_vertices(e, p) && k < count; ++k) {
                    const double v = binary_value(body.data() + at + k * size, p.type, swap);
                    if (!(v >= 0 && v < static_cast<double>(vertices)))
                        throw InputError(path, fmt::format("byte {} of the body", at + k * size),
                                         fmt::format("face {}: vertex index {:g} outside the {} vertices", i, v, vertices));
                }
                at += count * size;
            }
}

}  // namespace

void check_ply_counts(const std::string& path) {
    if (lower_extension(path) != ".ply") return;
    std::ifstream in(path, std::ios::binary);
    std::string line, format, declared_list;
    uint64_t min_bytes = 0;
    std::vector<PlyElement> elements;
    size_t header_lines = 0;
    bool ended = false;
    while (std::getline(in, line)) {
        ++header_lines;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        // A header is text: Assimp's reader ends it at a line that only starts with end_header
        // (NUL bytes after it), where these checks would read on (found by the mesh fuzzer:
        // its body then failed an assertion inside Assimp that aborts the process).
        if (!is_text(line)) throw InputError(path, fmt::format("line {}", header_lines), "the header holds a byte that is not text");
        std::istringstream ls(line);
        std::string word;
        ls >> word;
        const std::string where = fmt::format("line {}", header_lines);
        if (word == "format") {
            // One format, one Assimp reads: a second line or another name would have these
            // checks read the body other than Assimp does (the mesh fuzzer: an abort in Assimp).
            if (!format.empty()) throw InputError(path, where, "a second format line");
            ls >> format;
            if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
                throw InputError(path, where,
                                 "format \"" + format.substr(0, 40) + "\" is not ascii, binary_little_endian or binary_big_endian");
        } else if (word == "element") {
            PlyElement e;
            ls >> e.name >> e.count;
            if (!ls) throw InputError(path, where, "malformed element line");
            declared_list += fmt::format("{}{} {}", declared_list.empty() ? "" : ", ", e.count, e.name);
            elements.push_back(e);
        } else if (word == "property") {
            if (elements.empty()) throw InputError(path, where, "a property before any element");
            PlyProperty p;
            std::string count_name;
            ls >> p.type_name;
            if (p.type_name == "list") ls >> count_name >> p.type_name;
            ls >> p.name;
            p.type = scalar_of(p.type_name), p.count = count_name.empty() ? Scalar::None : scalar_of(count_name);
            if (p.type == Scalar::None || (!count_name.empty() && p.count == Scalar::None))
                throw InputError(path, where, "unknown property type \"" + (p.type == Scalar::None ? p.type_name : count_name) + "\"");
            // A list stores at least its length; a scalar its own size.
            const uint64_t size = size_of(count_name.empty() ? p.type : p.count);
            const uint64_t count = elements.back().count;
            if (count > 0 && size > (UINT64_MAX - min_bytes) / count) throw InputError(path, where, "element counts overflow");
            min_bytes += count * size;
            elements.back().properties.push_back(p);
        } else if (word == "end_header") {
            ended = true;
            break;
        }
        if (header_lines > 10000) throw InputError(path, "header", "no end_header in the first 10000 lines");
    }
    // Assimp's reader loops for ever on a header that never ends (found by the mesh fuzzer).
    if (!ended) throw InputError(path, "header", "the header has no end_header line");
    const auto vertex = std::find_if(elements.rbegin(), elements.rend(), [](const PlyElement& e) { return e.name == "vertex"; });
    if (vertex == elements.rend()) throw InputError(path, "header", "no vertex element");
    if (format == "ascii") return check_ascii_body(in, path, header_lines, elements, vertex->count);
    const auto body_start = static_cast<uint64_t>(in.tellg());
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (!ec && min_bytes > size - std::min(size, body_start))
        throw InputError(path, "header",
                         fmt::format("corrupted: the header declares {} (at least {} bytes); the file holds {}", declared_list, min_bytes,
                                     size - std::min(size, body_start)));
    if (format.empty()) return;  // no format line: Assimp refuses the file, naming it
    const std::string body((std::istreambuf_iterator<char>(in)), {});
    check_binary_body(body, path, elements, vertex->count, (format == "binary_big_endian") != (std::endian::native == std::endian::big));
}

}  // namespace bounce
