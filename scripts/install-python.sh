#!/usr/bin/env bash
# Makes `import bounce` work for the system Python, and for Debian's Blender, whose Python is the
# same: a bounce.pth naming BUILD/python (the module `make render` built) in the first
# site-packages folder this user may write: the system's (/usr/local/lib/python3.X/dist-packages,
# which Blender reads too) as root, else the user's. Nothing is copied: a rebuild is seen at once.
set -euo pipefail
build="$(cd "${1:-build}" && pwd)/python"
python="${PYTHON:-/usr/bin/python3}"
[ -x "$python" ] || python=python3
for dir in $("$python" -c 'import site, sysconfig; print(sysconfig.get_path("purelib")); print(site.getusersitepackages())'); do
  if mkdir -p "$dir" 2>/dev/null && [ -w "$dir" ]; then
    echo "$build" > "$dir/bounce.pth"
    echo "install-python: $dir/bounce.pth -> $build"
    exit 0
  fi
done
echo "install-python: no site-packages folder is writable here; use PYTHONPATH=$build" >&2
