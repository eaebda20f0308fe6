// The passes of a frame that an MPI job splits in row bands (docs/parallel.md): each process
// traces, gathers or shades the bands it owns (round robin) and every process takes every
// band, in band order, so the result is the one-process result whatever the number of ranks.
// The gathering and refinement passes split by tiles instead (cache/passes.h).
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

/// Calls `work(band)` for this process's row bands of `window` ({x0, x1, y0, y1}) and returns
/// every band's bytes, in band order, from whichever process made them (collective).
std::vector<std::string> in_row_bands(Communicator& comm, const std::array<int, 4>& window,
                                      const std::function<std::string(const std::array<int, 4>&)>& work);

/// The window of `deep` ({x0, x1, y0, y1}, full-image pixels).
std::array<int, 4> window_of(const DeepBuffer& deep);

/// The light of every fragment of `deep`, each band's made by `light(sub_window)` on the
/// process that owns it.
std::vector<Indirect> indirect_in_row_bands(Communicator& comm, const DeepBuffer& deep,
                                            const std::function<std::vector<Indirect>(const DeepBuffer&)>& light);

/// The fragments of `light` (parallel to deep.fragments) that lie in `band` of `deep`.
std::vector<Indirect> band_slice(const DeepBuffer& deep, const std::vector<Indirect>& light, const std::array<int, 4>& band);

}  // namespace bounce
