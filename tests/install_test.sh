#!/bin/sh
# Issue 63, item 6: `cmake --install` puts bounce, its libraries, headers and the lighting tool's
# page under a prefix, and the installed binary serves its page from there (not from the
# checkout it was built in). Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -eu
build=$1 src=$2
prefix=$(mktemp -d) out=$(mktemp -d)
trap 'kill $pid 2>/dev/null || true; rm -rf "$prefix" "$out"' EXIT
pid=
cmake --install "$build" --prefix "$prefix" >/dev/null
for f in bin/bounce lib/libbounce_core.a include/bounce/scene/scene.h share/bounce/web/index.html share/bounce/web/app.js; do
  [ -f "$prefix/$f" ] || { echo "install_test: $f was not installed"; exit 1; }
done
# The installed page is the one served: mark it, and look for the mark.
echo '<!-- installed copy -->' >> "$prefix/share/bounce/web/index.html"
"$prefix/bin/bounce" light "$src/scenes/cornell/cornell.json" --port 0 --out "$out/session" > "$out/log" 2>&1 &
pid=$!
url=
for i in $(seq 1 300); do
  url=$(grep -o 'http://[^ ]*' "$out/log" || true)
  [ -n "$url" ] && break
  sleep 0.1
done
[ -n "$url" ] || { echo "install_test: no URL"; cat "$out/log"; exit 1; }
token=${url##*token=}
base=${url%%/?token=*}
curl -sf "$url" | grep -q 'installed copy' || { echo "install_test: the page served is not the installed one"; exit 1; }
if [ -f "$prefix/share/bounce/three/build/three.module.js" ]; then
  curl -sf -H "Authorization: token $token" "$base/vendor/three/build/three.module.js" | head -c 100000 | grep -q 'REVISION' \
    || { echo "install_test: three.js is not served from the prefix"; exit 1; }
fi
echo "install_test: $prefix serves its page"
