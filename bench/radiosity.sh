#!/usr/bin/env bash
# Gather speed-up and error from radiosity textures (issue 3): the same brute-force render
# with gather hits shaded by shadow rays and by baked radiosity textures, both judged against
# a high-ray shadow-ray reference. Usage: bench/radiosity.sh [SCENE] [RES] [RAYS] [THREADS]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-scenes/cornell/cornell.json}
res=${2:-128x128}
rays=${3:-256}
threads=${4:-1}
bin=build/bounce
out=out/bench-radiosity
mkdir -p "$out"
# Every render shades the same deep buffer; the reference differs only in its seed.
"$bin" render "$scene" -o "$out/direct.exr" --res "$res" --spp 4 -q --deep-out "$out/deep.exr"
common=(--res "$res" --deep-in "$out/deep.exr" --gi brute -q)
run() {  # name, extra args...
    local name=$1; shift
    "$bin" render "$scene" -o "$out/$name.exr" "${common[@]}" --stats-json "$out/$name.json" "$@"
}
run ref --rays 4096 --set render.radiosity=false --set render.hit_light_samples=4 --seed 99 --threads 0
run shadow --rays "$rays" --set render.radiosity=false --threads "$threads"
run textures --rays "$rays" --threads "$threads"
g() { python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['phases_s'].get(sys.argv[2], 0))" "$@"; }
e() { "$bin" compare "$out/$1.exr" "$out/ref.exr" --layer indirect --json | python3 -c "import json,sys; print(json.load(sys.stdin)['indirect']['rel_rmse'])"; }
# Textures bake lazily inside the gather: its share (bake CPU time over the threads) is the bake.
tb=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j.get('radiosity_bake_cpu_s', 0) / max(1, j.get('threads', 1)))" "$out/textures.json")
ts=$(g "$out/shadow.json" gather); tt=$(python3 -c "import sys; print(float(sys.argv[1]) - float(sys.argv[2]))" "$(g "$out/textures.json" gather)" "$tb")
python3 - "$scene" "$res" "$rays" "$ts" "$tt" "$tb" "$(e shadow)" "$(e textures)" <<'PY'
import sys
scene, res, rays, ts, tt, tb, es, et = sys.argv[1:]
ts, tt, tb, es, et = map(float, (ts, tt, tb, es, et))
print(f"| scene | res | rays | gather, shadow rays | gather, textures | bake | speed-up | rel. RMSE shadow rays | rel. RMSE textures |")
print(f"|---|---|---|---|---|---|---|---|---|")
print(f"| {scene} | {res} | {rays} | {ts:.2f} s | {tt:.2f} s | {tb:.2f} s | {ts/tt:.2f}x | {100*es:.2f} % | {100*et:.2f} % |")
PY
