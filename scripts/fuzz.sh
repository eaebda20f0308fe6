#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (AddressSanitizer) and runs each for a bounded time
# on a copy of its seed corpus (render_fuzz renders 16x16 frames from fuzzed scenes and caches). Usage: scripts/fuzz.sh [SECONDS_PER_TARGET]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBOUNCE_BUILD_PYTHON=OFF -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DBOUNCE_FUZZ=ON -DBOUNCE_BUILD_TESTS=OFF -DBOUNCE_BUILD_BENCH=OFF >/dev/null
cmake --build build-fuzz --target cache_reader_fuzz scene_parser_fuzz render_fuzz deep_file_fuzz mesh_file_fuzz mesh_cache_fuzz -j "$(nproc)"
for target in cache_reader_fuzz:cache scene_parser_fuzz:scene render_fuzz:render deep_file_fuzz:deep mesh_file_fuzz:mesh mesh_cache_fuzz:meshcache; do
  name=${target%%:*}
  corpus=${target##*:}
  work=$(mktemp -d)
  cp fuzz/corpus/"$corpus"/* "$work"/
  echo "fuzz: $name for ${seconds}s"
  # An empty working directory: scene inputs cannot reach the project's mesh files.
  run=$(mktemp -d)
  status=0
  # A unit that runs for 60 s is a hang (libFuzzer's default waits 20 minutes). Assimp leaks a few
  # bytes on some glTF files it refuses: the mesh target does not count leaks (the others do).
  leaks=1
  [ "$name" = mesh_file_fuzz ] && leaks=0
  (cd "$run" && ASAN_OPTIONS="detect_leaks=$leaks" "$OLDPWD/build-fuzz/$name" "$work" -max_total_time="$seconds" \
     -rss_limit_mb=4096 -timeout=60 -detect_leaks=$leaks -max_len=65536 -print_final_stats=1 >log 2>&1) || status=$?
  if [ "$status" -ne 0 ]; then
    # The whole report and the input that failed, so a failure on another machine can be replayed
    # here: base64 -d > unit && build-fuzz/$name unit
    sed -n '/ERROR\|==[0-9]*==/,$p' "$run/log"
    for unit in "$run"/crash-* "$run"/leak-* "$run"/timeout-* "$run"/oom-*; do
      [ -f "$unit" ] && { echo "input $(basename "$unit") (base64):"; base64 "$unit"; }
    done
    exit "$status"
  fi
  tail -n 12 "$run/log"
  rm -rf "$work" "$run"
done
