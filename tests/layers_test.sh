#!/bin/sh
# The per-folder libraries' include trees (CMakeLists.txt): a scene/ source sees scene's own
# headers and its layers' (it compiles), and not render's (the include is not found).
# Usage: layers_test.sh CXX BUILD_DIR
set -u
cxx=$1 farm=$2/layers/scene
ok=$(printf '#include "bounce/scene/scene.h"\nint main() {}\n' | "$cxx" -std=c++20 -fsyntax-only -I"$farm" -x c++ - 2>&1) ||
  { echo "scene's own header does not compile in its tree: $ok"; exit 1; }
wrong=$(printf '#include "bounce/render/frame_plan.h"\nint main() {}\n' | "$cxx" -std=c++20 -fsyntax-only -I"$farm" -x c++ - 2>&1) &&
  { echo "scene/ compiled an include of render/"; exit 1; }
echo "$wrong" | grep -q 'bounce/render/frame_plan.h' || { echo "failed for another reason: $wrong"; exit 1; }
scripts_dir=$(dirname "$0")/../scripts
"$scripts_dir/check-includes" >/dev/null || { echo "check-includes finds wrong-way includes"; exit 1; }
echo "a wrong-way include does not compile; check-includes agrees with the sources"
