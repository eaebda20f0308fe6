// The passes of a frame that an MPI job splits in row bands (docs/parallel.md): each process
// traces, gathers or shades the bands it owns (RowBands: whole tile rows, round robin), so it
// holds the fragments of its own bands only, and the gathering and refinement passes judge the
// tiles of those bands (cache/passes.h). What is merged is merged in band order, so the result
// is the one-process result whatever the number of ranks.
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

/// Where the bands' bytes go: to every process, to process 0 only, or nowhere (each process
/// keeps its own bands; the others' come back empty).
enum class BandsTo { Everyone, First, Mine };

/// Calls `work(band)` ({x0, x1, y0, y1}, full-image pixels) for this process's row bands of
/// `window` (bands of whole `tile` rows) and returns the bands' bytes in band order (collective
/// unless Mine).
std::vector<std::string> in_row_bands(Communicator& comm, const std::array<int, 4>& window, int tile, BandsTo to,
                                      const std::function<std::string(const std::array<int, 4>&)>& work);

/// The window of `deep` ({x0, x1, y0, y1}, full-image pixels).
std::array<int, 4> window_of(const DeepBuffer& deep);

/// Visibility of `window` over the processes: each traces its bands; with `everyone`, every
/// process gets every band's fragments, else only its own (the other bands empty).
DeepBuffer visibility_in_row_bands(Communicator& comm, const Scene& scene, const SceneAccel& accel, Stats& stats,
                                   const std::array<int, 4>& window, bool everyone);

/// The light of the fragments of this process's bands of `deep` (the other bands' left zero),
/// each band's made by `light(sub_window)`.
std::vector<Indirect> indirect_in_row_bands(Communicator& comm, const DeepBuffer& deep, int tile,
                                            const std::function<std::vector<Indirect>(const DeepBuffer&)>& light);

/// The fragments of `light` (parallel to deep.fragments) that lie in `band` of `deep`.
std::vector<Indirect> band_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& band);

}  // namespace bounce
