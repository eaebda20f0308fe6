#!/usr/bin/env bash
# Rewrites the parameter table of docs/scene-format.md (between its params markers) from
# `bounce params --markdown`; the Params.TheDocsTableIsTheGeneratedOne test checks they agree.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/bounce}
python3 - "$bin" <<'PY'
import subprocess, sys
md = subprocess.run([sys.argv[1], "params", "--markdown"], capture_output=True, text=True, check=True).stdout
path = "docs/scene-format.md"
s = open(path).read()
a = s.index("<!-- params:begin -->") + len("<!-- params:begin -->\n")
b = s.index("<!-- params:end -->")
open(path, "w").write(s[:a] + md + s[b:])
PY
