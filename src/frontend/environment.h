// What every front end of bounce (the command line, the tests' and benches' drivers) reads from
// the process's environment, in one place: the library reads none (issue 63), so each front end
// hands these on explicitly.
#pragma once

#include "bounce/scene/load_resources.h"
#include "bounce/scene/mesh_cache.h"
#include "bounce/scene/scene_load.h"

namespace bounce {

/// What the environment names for loading scenes (docs/scene-format.md): the mesh cache in
/// $BOUNCE_MESH_CACHE (unset: none; one MeshCache per folder for the process); embedded images in
/// $BOUNCE_IMAGE_CACHE, else $XDG_CACHE_HOME/bounce/images, else ~/.cache/bounce/images, else
/// /tmp/bounce-images-<uid>; and the process's remembered file hashes.
LoadResources load_resources_from_environment();
/// LoadOptions whose resources are load_resources_from_environment()'s (the rest as defaulted).
LoadOptions load_options_from_environment();
/// The process's mesh caches' counts, summed over the folders its loads used.
MeshCacheCounts mesh_cache_counts();

/// Whether an MPI launcher (mpirun, srun) started this process.
bool launched_by_mpi();

}  // namespace bounce
