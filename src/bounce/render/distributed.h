// The passes of a frame that an MPI job splits by tiles (docs/parallel.md): the image's tiles
// (make_tiles, the scene's tile size) go round robin to the processes, and every pass uses
// that one split, so a process traces, judges, refines and shades only its own tiles and holds
// only their fragments. What is merged is merged in tile order, so the result is the
// one-process result whatever the number of ranks. (The gathering and refinement passes take
// their tiles through cache/passes.h.)
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "bounce/core/communicator.h"
#include "bounce/core/image.h"
#include "bounce/deep/deep_buffer.h"
#include "bounce/gather/gather.h"

namespace bounce {

/// Where the tiles' bytes go: to every process, to process 0 only, or nowhere (each process
/// keeps its own tiles'; the others' come back empty).
enum class TilesTo { Everyone, First, Mine };

/// Calls `work(tile)` ({x0, x1, y0, y1}, full-image pixels) for this process's tiles of
/// `window` and returns the tiles' bytes in tile order (collective unless Mine).
std::vector<std::string> in_tiles(Communicator& comm, const std::array<int, 4>& window, int tile, TilesTo to,
                                  const std::function<std::string(const std::array<int, 4>&)>& work);

/// The window of `deep` ({x0, x1, y0, y1}, full-image pixels).
std::array<int, 4> window_of(const DeepBuffer& deep);

/// Visibility of `window` over the processes: each traces its tiles; with `everyone`, every
/// process gets every tile's fragments, else only its own (the other pixels empty).
DeepBuffer visibility_in_tiles(Communicator& comm, const Scene& scene, const SceneAccel& accel, const VisibilitySettings& settings,
                               int tile_size, Stats& stats, const std::array<int, 4>& window, bool everyone);

/// The light of the fragments of this process's tiles of `deep` (the others' left zero), each
/// tile's made by `light(sub_window)`.
std::vector<Indirect> indirect_in_tiles(Communicator& comm, const DeepBuffer& deep, int tile,
                                        const std::function<std::vector<Indirect>(const DeepBuffer&)>& light);

/// The entries of `light` (parallel to deep.fragments) of the fragments in window `w` of
/// `deep`, in the order sub_window(deep, w) holds them.
std::vector<Indirect> window_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& w);

}  // namespace bounce
