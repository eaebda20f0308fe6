#include "bounce/scene/keyframes.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "bounce/core/math.h"
#include "bounce/config/params.h"

namespace bounce {

using nlohmann::json;

namespace {

bool is_keyed(const json& v) { return v.is_object() && v.contains("keys"); }

enum class Interp { Linear, Smooth, Step };

struct Track {
    std::vector<double> t;
    std::vector<std::vector<double>> v;  ///< per key, the value's numbers (1 for a number)
    bool scalar = true;
    Interp interp = Interp::Linear;
};

Track read_track(const json& keyed, const std::string& ptr, const JsonContext& ctx) {
    for (auto it = keyed.begin(); it != keyed.end(); ++it)
        if (it.key() != "keys" && it.key() != "interpolation")
            ctx.fail(ptr + "/" + it.key(), fmt::format("unknown key \"{}\" in a keyed value (keys: keys, interpolation)", it.key()));
    Track tr;
    if (keyed.contains("interpolation")) {
        const json& i = keyed["interpolation"];
        const std::string name = i.is_string() ? i.get<std::string>() : "";
        if (name == "linear")
            tr.interp = Interp::Linear;
        else if (name == "smooth")
            tr.interp = Interp::Smooth;
        else if (name == "step")
            tr.interp = Interp::Step;
        else
            ctx.fail(ptr + "/interpolation", fmt::format("unknown interpolation {} (valid: linear, smooth, step)", i.dump()));
    }
    const json& keys = keyed["keys"];
    if (!keys.is_array() || keys.empty()) ctx.fail(ptr + "/keys", "expected a non-empty array of [frame, value] keys");
    for (size_t k = 0; k < keys.size(); ++k) {
        const std::string kp = fmt::format("{}/keys/{}", ptr, k);
        const json& key = keys[k];
        if (!key.is_array() || key.size() != 2) ctx.fail(kp, "expected [frame, value]");
        if (!key[0].is_number() || !is_frame_number(key[0].get<double>()))
            ctx.fail(kp + "/0", fmt::format("a key's frame must be a finite number within +-{:g}", kMaxFrame));
        const double t = key[0].get<double>();
        if (!tr.t.empty() && t <= tr.t.back())
            ctx.fail(kp + "/0", t == tr.t.back() ? fmt::format("frame {} is keyed twice", t)
                                                 : fmt::format("keys out of order (frame {} after frame {})", t, tr.t.back()));
        const json& value = key[1];
        std::vector<double> nums;
        if (value.is_number()) {
            nums.push_back(value.get<double>());
        } else if (value.is_array() && !value.empty()) {
            tr.scalar = false;
            for (const json& x : value) {
                if (!x.is_number()) ctx.fail(kp + "/1", "a keyed value is a number or an array of numbers");
                nums.push_back(x.get<double>());
            }
        } else {
            ctx.fail(kp + "/1", "a keyed value is a number or an array of numbers");
        }
        for (size_t i = 0; i < nums.size(); ++i)
            if (!std::isfinite(nums[i]) || std::fabs(nums[i]) > 1e30) ctx.fail(kp + "/1", fmt::format("{} is not a finite value", nums[i]));
        if (!tr.v.empty() && (nums.size() != tr.v.back().size() || value.is_number() != tr.scalar))
            ctx.fail(kp + "/1", "every key must hold a value of the same shape");
        tr.t.push_back(t);
        tr.v.push_back(std::move(nums));
    }
    return tr;
}

/// Unit quaternion (w, x, y, z) of a rotation [degrees, axis].
std::array<double, 4> to_quaternion(const std::vector<double>& r, const std::string& ptr, const JsonContext& ctx) {
    if (r.size() != 4) ctx.fail(ptr, "a keyed rotate holds [degrees, axis_x, axis_y, axis_z]");
    const double len = std::sqrt(r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
    if (!(len > 0)) ctx.fail(ptr, "rotation axis is zero");
    const double half = 0.5 * r[0] * std::numbers::pi / 180;
    const double s = std::sin(half) / len;
    return {std::cos(half), r[1] * s, r[2] * s, r[3] * s};
}

/// Hermite interpolation with Catmull-Rom tangents (non-uniform spacing): C1 through the keys.
double smooth_value(const Track& tr, const std::vector<std::vector<double>>& v, size_t i, size_t c, double t) {
    const size_t n = tr.t.size();
    const auto tangent = [&](size_t k) {
        const size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
        return (v[b][c] - v[a][c]) / (tr.t[b] - tr.t[a]);
    };
    const double h = tr.t[i + 1] - tr.t[i], s = (t - tr.t[i]) / h;
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * v[i][c] + (s3 - 2 * s2 + s) * h * tangent(i) + (-2 * s3 + 3 * s2) * v[i + 1][c] +
           (s3 - s2) * h * tangent(i + 1);
}

/// The track's value at `t`: clamped outside its keys.
std::vector<double> sample(const Track& tr, const std::vector<std::vector<double>>& v, double t) {
    const size_t n = tr.t.size();
    if (t <= tr.t.front()) return v.front();
    if (t >= tr.t.back()) return v.back();
    size_t i = 0;
    while (tr.t[i + 1] <= t) ++i;
    if (tr.interp == Interp::Step) return v[i];
    std::vector<double> out(v[i].size());
    const double s = (t - tr.t[i]) / (tr.t[i + 1] - tr.t[i]);
    for (size_t c = 0; c < out.size(); ++c)
        out[c] = tr.interp == Interp::Linear || n < 3 ? v[i][c] + s * (v[i + 1][c] - v[i][c]) : smooth_value(tr, v, i, c, t);
    return out;
}

/// A keyed rotation at `t`, interpolated as quaternions (each key on the hemisphere of the one
/// before it, so the path is the short one), as [degrees, axis].
json sample_rotation(const Track& tr, double t, const std::string& ptr, const JsonContext& ctx) {
    std::vector<std::vector<double>> q;
    for (size_t k = 0; k < tr.v.size(); ++k) {
        auto qk = to_quaternion(tr.v[k], fmt::format("{}/keys/{}/1", ptr, k), ctx);
        std::vector<double> v(qk.begin(), qk.end());
        // Half a turn apart both ways are as short: keep the direction the angles were written in.
        if (!q.empty() && v[0] * q.back()[0] + v[1] * q.back()[1] + v[2] * q.back()[2] + v[3] * q.back()[3] < -1e-9)
            for (double& x : v) x = -x;
        q.push_back(v);
    }
    std::vector<double> r = sample(tr, q, t);
    const double len = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]);
    for (double& x : r) x /= len;
    const double angle = 2 * std::acos(std::clamp(r[0], -1.0, 1.0)) * 180 / std::numbers::pi;
    const double s = std::sqrt(std::max(0.0, 1 - r[0] * r[0]));
    if (s < 1e-12) return json::array({0.0, 0.0, 1.0, 0.0});
    return json::array({angle, r[1] / s, r[2] / s, r[3] / s});
}

/// Replaces keyed values under `v` (at pointer `ptr`) in place.
void evaluate(json& v, const std::string& ptr, double frame, const JsonContext& ctx) {
    if (is_keyed(v)) {
        if (!animatable_pointer(ptr))
            ctx.fail(ptr, "this value cannot be animated (bounce params lists what can: the \"animatable\" column)");
        const Track tr = read_track(v, ptr, ctx);
        if (ptr.ends_with("/transform/rotate")) {
            v = sample_rotation(tr, frame, ptr, ctx);
            return;
        }
        const std::vector<double> x = sample(tr, tr.v, frame);
        v = tr.scalar ? json(x[0]) : json(x);
        return;
    }
    if (v.is_object()) {
        for (auto it = v.begin(); it != v.end(); ++it) evaluate(it.value(), ptr + "/" + it.key(), frame, ctx);
    } else if (v.is_array()) {
        for (size_t i = 0; i < v.size(); ++i) evaluate(v[i], fmt::format("{}/{}", ptr, i), frame, ctx);
    }
}

}  // namespace

bool has_keys(const json& doc) {
    if (is_keyed(doc)) return true;
    if (doc.is_object())
        for (const auto& [k, v] : doc.items())
            if (k != "description" && has_keys(v)) return true;
    if (doc.is_array())
        for (const json& v : doc)
            if (has_keys(v)) return true;
    return false;
}

bool keys_light(const json& keyed) {
    if (!keyed.is_object()) return false;
    if (keyed.contains("lights") && has_keys(keyed["lights"])) return true;
    if (keyed.contains("materials") && keyed["materials"].is_object())
        for (const auto& [name, m] : keyed["materials"].items())
            if (m.is_object() && m.contains("emission") && has_keys(m["emission"])) return true;
    return false;
}

ShotSettings read_shot(const json& doc, const JsonContext& ctx) {
    ShotSettings shot;
    if (!doc.contains("animation")) {
        if (has_keys(doc)) ctx.fail("", "the scene has keyed values but no \"animation\" block ({\"fps\": 24, \"frames\": [1, 48]})");
        return shot;
    }
    JsonReader a(doc["animation"], "/animation", ctx, {"fps", "frames"});
    shot.animated = true;
    shot.fps = a.number("fps", 24, 1e-3, 1e4);
    if (!a.has("frames")) a.fail("", "missing required key \"frames\" ([first, last])");
    const json& f = a.raw("frames");
    if (!f.is_array() || f.size() != 2) a.fail("frames", "expected [first, last]");
    shot.first =
        static_cast<int>(json_integer(f[0], -kMaxFrame, kMaxFrame, [&](const std::string& m) { ctx.fail("/animation/frames/0", m); }));
    shot.last =
        static_cast<int>(json_integer(f[1], -kMaxFrame, kMaxFrame, [&](const std::string& m) { ctx.fail("/animation/frames/1", m); }));
    if (shot.last < shot.first) a.fail("frames", fmt::format("the last frame {} comes before the first {}", shot.last, shot.first));
    return shot;
}

json evaluate_keys(const json& doc, double frame, const JsonContext& ctx) {
    json out = doc;
    for (auto it = out.begin(); it != out.end(); ++it)
        if (it.key() != "description" && it.key() != "animation") evaluate(it.value(), "/" + it.key(), frame, ctx);
    return out;
}

}  // namespace bounce
