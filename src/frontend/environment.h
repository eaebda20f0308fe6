// What every front end of bounce (the command line, the tests' and benches' drivers) reads from
// the process's environment, in one place: the library reads none (issue 63), so each front end
// hands these on explicitly.
#pragma once

#include "bounce/scene/load_folders.h"
#include "bounce/scene/scene_load.h"

namespace bounce {

/// The folders the environment names for loading scenes (docs/scene-format.md): the mesh cache
/// $BOUNCE_MESH_CACHE (unset: none); embedded images in $BOUNCE_IMAGE_CACHE, else
/// $XDG_CACHE_HOME/bounce/images, else ~/.cache/bounce/images, else /tmp/bounce-images-<uid>.
LoadFolders load_folders_from_environment();
/// LoadOptions whose folders are load_folders_from_environment()'s (the rest as defaulted).
LoadOptions load_options_from_environment();

/// Whether an MPI launcher (mpirun, srun) started this process.
bool launched_by_mpi();

}  // namespace bounce
