// The deep buffer ("deep file"): primary visibility cached per pixel as a list of fragments.
// Shading (direct now, gathering and the cache later) starts from it, so a frame can be
// re-shaded without re-tracing primary visibility. Stored as an OpenEXR deep image.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "bounce/accel/accel.h"
#include "bounce/core/communicator.h"
#include "bounce/core/math.h"
#include "bounce/core/progress.h"
#include "bounce/core/random.h"
#include "bounce/core/stats.h"
#include "bounce/core/tiles.h"
#include "bounce/scene/scene.h"

namespace bounce {

/// One visible surface in a pixel: the jittered subsamples that hit the same surface, merged.
/// Normals face the camera.
struct Fragment {
    Vec3 p;       ///< position (fine surface)
    Vec3 n;       ///< shading normal
    Vec3 ng;      ///< geometric normal
    Vec3 p_base;  ///< un-displaced position (where cache records live); = p without displacement
    Vec3 n_base;  ///< un-displaced (un-bumped) normal
    Vec2 uv;
    uint32_t material = 0;
    uint32_t object = 0;
    uint32_t prim = 0;    ///< fine-tessellation triangle of the first subsample
    float depth = 0;      ///< distance from the camera
    float weight = 0;     ///< fraction of the pixel's subsamples (coverage)
    float footprint = 0;  ///< world-space width of one pixel at p (ray differentials)
    /// Fur: the strand's unit tangent (root to tip; zero on surfaces) and the position along
    /// it (0 root, 1 tip). A hair fragment's p_base / n_base are its strand's root and the
    /// growing surface's normal there, uv the root's, prim the strand.
    Vec3 tangent{0};
    float strand_v = 0;
    bool is_hair() const { return tangent.x != 0 || tangent.y != 0 || tangent.z != 0; }
    bool operator==(const Fragment&) const = default;
};

/// Fragments of a window of the image (the crop, or the full frame).
struct DeepBuffer {
    int full_width = 0, full_height = 0;        ///< the whole image
    int x0 = 0, y0 = 0, width = 0, height = 0;  ///< the window this buffer covers
    int spp = 0;
    uint64_t seed = 0;
    uint64_t scene_fingerprint = 0;  ///< Scene::visibility_fingerprint()
    std::vector<uint32_t> offsets;   ///< width*height+1 prefix sums into fragments
    std::vector<Fragment> fragments;

    size_t pixel_count() const { return static_cast<size_t>(width) * height; }
    /// Fragments of window pixel (x, y) (window coordinates).
    std::span<const Fragment> pixel(int x, int y) const {
        size_t i = static_cast<size_t>(y) * width + x;
        return {fragments.data() + offsets[i], fragments.data() + offsets[i + 1]};
    }
    bool operator==(const DeepBuffer&) const = default;
};

/// Runs `pixel(wx, wy, first)` for every pixel of `deep` (window coordinates; `first` indexes
/// the pixel's first fragment), tile by tile in parallel with TBB, reporting one progress unit
/// per tile under `name`. Work order never affects results: each pixel writes its own slots.
/// With `comm`, only the tiles this process owns (it holds only their fragments).
template <typename PixelFn>
void for_each_pixel_in_tiles(const DeepBuffer& deep, int tile, ProgressSink* sink, const char* name, PixelFn&& pixel,
                             TileOrder order = TileOrder::Rows, const Communicator* comm = nullptr) {
    auto tiles = make_tiles(deep.width, deep.height, tile, order);
    if (comm) std::erase_if(tiles, [comm](const Tile& t) { return !comm->owns(static_cast<size_t>(t.index)); });
    Progress progress(sink, name, tiles.size());
    for_each_tile(tiles, [&](const Tile& t) {
        for (int wy = t.y0; wy < t.y1; ++wy, sink ? sink->check_cancel() : void())
            for (int wx = t.x0; wx < t.x1; ++wx)
                pixel(wx, wy, static_cast<size_t>(deep.offsets[static_cast<size_t>(wy) * deep.width + wx]));
        progress.add();
    });
}

/// The random stream of fragment `k` of full-image pixel (x, y): everything shading does at a
/// fragment (light samples, gathers) draws from it, so results never depend on threads or crop.
inline RandomStream fragment_stream(uint64_t seed, int x, int y, uint32_t k) {
    return RandomStream(seed, static_cast<uint64_t>(y) * 65536u + static_cast<uint64_t>(x), 1u + k);
}

/// The pinhole camera of a scene: rays through continuous full-image pixel coordinates.
class CameraRays {
  public:
    explicit CameraRays(const Camera& cam);
    /// Unnormalised direction through pixel position (px, py) (0..width, 0..height, y down).
    Vec3 direction(float px, float py) const;
    /// The thin lens's ray through pixel position (px, py) from lens point (lu, lv) in [0,1)^2
    /// (uniform over the aperture's disc): it crosses the pinhole ray on the plane in focus.
    /// Returns the origin; `dir` gets the unit direction. A pinhole gives origin() and the
    /// pinhole direction.
    /// `time` in [0, 1] over the shutter: a camera that moves in it (Camera::moves_in_shutter())
    /// is where its pose, interpolated linearly between shutter open and close, puts it.
    Vec3 lens_ray(float px, float py, float lu, float lv, Vec3& dir, float time = 0) const;
    Vec3 origin() const { return view_.pos; }
    /// World-space width of one pixel at a hit at distance t along unit direction d on a
    /// surface of normal n: the narrowest extent of the pixel's projection (from the ray
    /// differentials; grazing angles are capped).
    float footprint(const Vec3& d, float t, const Vec3& n) const;
    /// Full-image pixel position of world point p; false if p is behind the camera.
    bool project(const Vec3& p, float& px, float& py) const;
    /// True when p is in front of the camera and projects into the pixel window
    /// [x0, x1) x [y0, y1) (full-image coordinates).
    bool projects_into(const Vec3& p, const std::array<int, 4>& window) const;

  private:
    /// A pose's frame: where rays leave and their directions' axes (forward has unit length).
    struct View {
        Vec3 pos, forward, right, up;
        float scale = 1;  ///< tan(fov / 2)
    };
    static View view_of(const Camera::Pose& pose);
    Vec3 direction(const View& v, float px, float py) const;
    View view_;  ///< the pose at the frame's time
    float aspect_ = 1;
    std::array<Camera::Pose, 2> shutter_{};
    bool moves_ = false;
    float aperture_ = 0, focus_ = 1;  ///< lens diameter and distance of the plane in focus
    int width_ = 1, height_ = 1;
};

/// Traces `spp` jittered subsamples per pixel against the fine tessellation and merges those
/// that hit the same surface into fragments. Deterministic for a given seed, whatever the
/// thread count or crop. `settings`: the samples, the seed and the crop.
DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, const VisibilitySettings& settings, Stats& stats,
                             ProgressSink* progress);
/// Same, for window {x0, x1, y0, y1} (full-image pixels, ends exclusive).
DeepBuffer render_visibility(const Scene& scene, const SceneAccel& accel, const VisibilitySettings& settings, Stats& stats,
                             ProgressSink* progress, const std::array<int, 4>& window);

/// The window a camera renders: the crop, or the full frame ({x0, x1, y0, y1}).
std::array<int, 4> frame_window(const Camera& camera, const VisibilitySettings& settings);
/// The fragments of window `w` of `deep`, which must contain it.
DeepBuffer sub_window(const DeepBuffer& deep, const std::array<int, 4>& w);

/// A window's fragments as bytes for another process of the same build (an MPI exchange), and back.
std::string serialize_window(const DeepBuffer& deep);
DeepBuffer parse_window(const std::string& bytes);
/// One window `w` ({x0, x1, y0, y1}) of `scene` from the fragments of some of its tiles
/// (each a DeepBuffer of its own window inside `w`); pixels no tile covers are empty.
DeepBuffer assemble_tiles(const Scene& scene, const VisibilitySettings& settings, const std::array<int, 4>& w,
                          const std::vector<DeepBuffer>& tiles);
/// A window of `scene`'s image with no fragments (stamped with the settings' samples and seed).
DeepBuffer empty_window(const Scene& scene, const VisibilitySettings& settings, const std::array<int, 4>& window);

/// Throws InputError (naming the camera) if no camera ray hits any geometry.
void check_camera_sees_geometry(const Scene& scene, const SceneAccel& accel);

/// Writes an OpenEXR deep scanline file (written to a temporary name and renamed). With
/// `colour` (parallel to deep.fragments: what each fragment adds to the beauty), also R, G, B
/// for deep compositing: A is then each sample's alpha for over-compositing in depth order
/// (coverage / the coverage not yet covered in front of it), so flattening gives the beauty's
/// colour and alpha, and the coverage itself goes to a `coverage` channel (read_deep takes it).
void write_deep(const std::string& path, const DeepBuffer& deep, const std::vector<Color>* colour = nullptr);
/// Reads a deep file written by write_deep; InputError on anything malformed: every field of
/// every fragment is checked (invalid_fragment_field), ids against the scene later
/// (validate_deep_for_scene).
DeepBuffer read_deep(const std::string& path);
/// The deep channel of the first field of `f` out of range ("P", "Nref" ...), or nullptr:
/// coordinates finite within +-1e18, normals and hair tangents unit length, weight in (0, 1],
/// footprint > 0, depth >= 0, v in [0, 1].
const char* invalid_fragment_field(const Fragment& f);

}  // namespace bounce
