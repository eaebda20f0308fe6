// The pinhole camera: rays through pixel positions, footprints and projection.
#include <cmath>

#include "bounce/deep/deep_buffer.h"
#include "bounce/core/sampling.h"

namespace bounce {

CameraRays::CameraRays(const Camera& cam) : pos_(cam.position), width_(cam.width), height_(cam.height) {
    forward_ = normalize(cam.look_at - cam.position);
    right_ = normalize(cross(forward_, cam.up));
    up_ = cross(right_, forward_);
    scale_ = std::tan(cam.fov * kPi / 360.0f);
    aspect_ = static_cast<float>(cam.width) / static_cast<float>(cam.height);
    aperture_ = cam.aperture;
    focus_ = cam.focus_distance > 0 ? cam.focus_distance : length(cam.look_at - cam.position);
}

Vec3 CameraRays::lens_ray(float px, float py, float lu, float lv, Vec3& dir) const {
    const Vec3 d = direction(px, py);  // forward has unit length along the view: d reaches the plane at focus_ / 1
    if (aperture_ <= 0) {
        dir = normalize(d);
        return pos_;
    }
    const Vec2 disc = concentric_disc(lu, lv);
    const Vec3 origin = pos_ + (right_ * disc.x + up_ * disc.y) * (0.5f * aperture_);
    dir = normalize(pos_ + d * focus_ - origin);
    return origin;
}

Vec3 CameraRays::direction(float px, float py) const {
    float sx = (2 * px / static_cast<float>(width_) - 1) * aspect_ * scale_;
    float sy = (1 - 2 * py / static_cast<float>(height_)) * scale_;
    return forward_ + right_ * sx + up_ * sy;
}

float CameraRays::footprint(const Vec3& d, float t, const Vec3& n) const {
    float s = 2 * scale_ / static_cast<float>(height_);
    Vec3 dx = right_ * s, dy = up_ * -s;
    float nd = dot(n, d);
    nd = std::copysign(std::max(std::abs(nd), 0.05f * length(d)), nd);
    float tau = t / length(d);
    Vec3 px = (dx - d * (dot(n, dx) / nd)) * tau, py = (dy - d * (dot(n, dy) / nd)) * tau;
    // The pixel's narrowest world extent (parallelogram area over its longer side), not
    // sqrt(area): on surfaces seen at grazing angles a record's reach in pixels along the
    // foreshortened direction would otherwise be far beyond max_spacing.
    return length(cross(px, py)) / std::max(length(px), length(py));
}

bool CameraRays::project(const Vec3& p, float& px, float& py) const {
    Vec3 v = p - pos_;
    float z = dot(v, forward_);
    if (z <= 0) return false;
    float sx = dot(v, right_) / z, sy = dot(v, up_) / z;
    px = (sx / (aspect_ * scale_) + 1) * 0.5f * static_cast<float>(width_);
    py = (1 - sy / scale_) * 0.5f * static_cast<float>(height_);
    return true;
}

bool CameraRays::projects_into(const Vec3& p, const std::array<int, 4>& w) const {
    float px, py;
    return project(p, px, py) && px >= static_cast<float>(w[0]) && px < static_cast<float>(w[1]) &&
           py >= static_cast<float>(w[2]) && py < static_cast<float>(w[3]);
}

// ------------------------------------------------------------------------------------------
// Visibility

}  // namespace bounce
