// The pinhole camera: rays through pixel positions, footprints and projection.
#include <cmath>

#include "bounce/deep/deep_buffer.h"
#include "bounce/core/sampling.h"

namespace bounce {

CameraRays::View CameraRays::view_of(const Camera::Pose& pose) {
    View v;
    v.pos = pose.position;
    v.forward = normalize(pose.look_at - pose.position);
    v.right = normalize(cross(v.forward, pose.up));
    v.up = cross(v.right, v.forward);
    v.scale = std::tan(pose.fov * kPi / 360.0f);
    return v;
}

CameraRays::CameraRays(const Camera& cam) : view_(view_of(cam.pose())), width_(cam.width), height_(cam.height) {
    aspect_ = static_cast<float>(cam.width) / static_cast<float>(cam.height);
    aperture_ = cam.aperture;
    focus_ = cam.focus_distance > 0 ? cam.focus_distance : length(cam.look_at - cam.position);
    shutter_ = cam.shutter_pose;
    moves_ = cam.moves_in_shutter();
}

Vec3 CameraRays::lens_ray(float px, float py, float lu, float lv, Vec3& dir, float time) const {
    View v = view_;
    if (moves_) {
        const Camera::Pose &a = shutter_[0], &b = shutter_[1];
        const auto mix = [time](const Vec3& x, const Vec3& y) { return x + (y - x) * time; };
        v = view_of({mix(a.position, b.position), mix(a.look_at, b.look_at), mix(a.up, b.up), a.fov + (b.fov - a.fov) * time});
    }
    const Vec3 d = direction(v, px, py);  // forward has unit length along the view: d reaches the plane at focus_ / 1
    if (aperture_ <= 0) {
        dir = normalize(d);
        return v.pos;
    }
    const Vec2 disc = concentric_disc(lu, lv);
    const Vec3 origin = v.pos + (v.right * disc.x + v.up * disc.y) * (0.5f * aperture_);
    dir = normalize(v.pos + d * focus_ - origin);
    return origin;
}

Vec3 CameraRays::direction(float px, float py) const { return direction(view_, px, py); }

Vec3 CameraRays::direction(const View& v, float px, float py) const {
    float sx = (2 * px / static_cast<float>(width_) - 1) * aspect_ * v.scale;
    float sy = (1 - 2 * py / static_cast<float>(height_)) * v.scale;
    return v.forward + v.right * sx + v.up * sy;
}

float CameraRays::footprint(const Vec3& d, float t, const Vec3& n) const {
    float s = 2 * view_.scale / static_cast<float>(height_);
    Vec3 dx = view_.right * s, dy = view_.up * -s;
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
    Vec3 v = p - view_.pos;
    float z = dot(v, view_.forward);
    if (z <= 0) return false;
    float sx = dot(v, view_.right) / z, sy = dot(v, view_.up) / z;
    px = (sx / (aspect_ * view_.scale) + 1) * 0.5f * static_cast<float>(width_);
    py = (1 - sy / view_.scale) * 0.5f * static_cast<float>(height_);
    return true;
}

bool CameraRays::projects_into(const Vec3& p, const std::array<int, 4>& w) const {
    float px, py;
    return project(p, px, py) && px >= static_cast<float>(w[0]) && px < static_cast<float>(w[1]) && py >= static_cast<float>(w[2]) &&
           py < static_cast<float>(w[3]);
}

// ------------------------------------------------------------------------------------------
// Visibility

}  // namespace bounce
