#!/usr/bin/env bash
# Builds the browser viewer into a folder laid out as it is served:
#   index.html viewer.js                    the page (web/viewer/)
#   lodkit/*.js lodkit/lodkit.wasm          the loaders, the worker, the decoders
#   three/build/… three/examples/jsm/…      the three.js files the page imports
#   3d-tiles-renderer/build/…               3DTilesRendererJS (tilesets), its three.js entry
# index.html gets a <link rel="modulepreload"> for every module a tileset's
# first frame needs (viewer.js's static imports and theirs: listed below,
# 3DTilesRendererJS's chunks as found), so the browser fetches them all at
# once instead of one import level at a time.
# The .pop/.mco decoders (lodkit/) and the PLY reader are not among them:
# the viewer imports those only when it opens such a file.
# Usage: scripts/build-web.sh [OUT_DIR]   (default web/dist)
# Installs what it needs: the wasm32-unknown-unknown target (rustup) and the
# npm packages of web/package-lock.json (npm ci). crates/cli/build.rs runs it
# when the viewer is missing or stale; it may also be run by hand.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/web/dist}
cargo_bin=${CARGO:-cargo}

# Run from a build script, this inherits the outer cargo's variables (its
# target, profile, flags, jobserver): clear them so the nested build is an
# ordinary one. CARGO_HOME and RUSTUP_* stay (where the toolchain lives).
for v in $(env | sed -n 's/^\(CARGO_[A-Za-z0-9_]*\)=.*/\1/p'); do
  [ "$v" = CARGO_HOME ] || unset "$v"
done
unset CARGO RUSTC RUSTDOC RUSTC_WRAPPER RUSTC_WORKSPACE_WRAPPER RUSTFLAGS RUSTDOCFLAGS \
  RUSTC_LINKER TARGET HOST OUT_DIR PROFILE OPT_LEVEL DEBUG NUM_JOBS MAKEFLAGS MFLAGS 2>/dev/null || true

if command -v rustup >/dev/null 2>&1; then
  if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
    echo "build-web: rustup target add wasm32-unknown-unknown" >&2
    rustup target add wasm32-unknown-unknown >&2
  fi
fi

# Its own target folder: the outer build holds the lock on target/.
echo "build-web: building lodkit-wasm (release, wasm32-unknown-unknown)" >&2
CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true \
  "$cargo_bin" build --release --quiet -p lodkit-wasm --target wasm32-unknown-unknown \
  --manifest-path "$root/Cargo.toml" --target-dir "$root/target/web-wasm" >&2
wasm=$root/target/web-wasm/wasm32-unknown-unknown/release/lodkit_wasm.wasm

web=$root/web
if [ ! -f "$web/node_modules/three/package.json" ] || [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  echo "build-web: npm ci in web/" >&2
  (cd "$web" && npm ci --no-audit --no-fund --ignore-scripts --loglevel=error) >&2
fi

three=$web/node_modules/three
tmp=$(mktemp -d "${out%/}.tmp.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/lodkit" "$tmp/three/build" "$tmp/three/examples/jsm/controls" \
  "$tmp/three/examples/jsm/loaders" "$tmp/three/examples/jsm/utils" "$tmp/three/examples/jsm/libs" \
  "$tmp/3d-tiles-renderer/build"
cp "$web/viewer/viewer.js" "$tmp/"
cp "$web"/src/*.js "$tmp/lodkit/"
cp "$wasm" "$tmp/lodkit/lodkit.wasm"
cp "$three/LICENSE" "$tmp/three/LICENSE"
cp "$three/build/three.module.js" "$three/build/three.core.js" "$tmp/three/build/"
cp "$three/examples/jsm/controls/OrbitControls.js" "$tmp/three/examples/jsm/controls/"
cp "$three/examples/jsm/loaders/GLTFLoader.js" "$three/examples/jsm/loaders/PLYLoader.js" "$tmp/three/examples/jsm/loaders/"
cp "$three/examples/jsm/utils/BufferGeometryUtils.js" "$three/examples/jsm/utils/SkeletonUtils.js" "$tmp/three/examples/jsm/utils/"
cp "$three/examples/jsm/libs/meshopt_decoder.module.js" "$tmp/three/examples/jsm/libs/"
# 3DTilesRendererJS: its three.js entry and the chunks it imports (by
# relative path; their names carry a content hash, so they are followed
# from the entry rather than listed here).
tiles=$web/node_modules/3d-tiles-renderer
cp "$tiles/LICENSE" "$tmp/3d-tiles-renderer/LICENSE"
pending=(index.three.js)
tiles_js=()
while [ ${#pending[@]} -gt 0 ]; do
  f=${pending[0]}
  pending=("${pending[@]:1}")
  [ -f "$tmp/3d-tiles-renderer/build/$f" ] && continue
  cp "$tiles/build/$f" "$tmp/3d-tiles-renderer/build/$f"
  tiles_js+=("3d-tiles-renderer/build/$f")
  mapfile -t deps < <(grep -o 'from "\./[^"]*\.js"' "$tiles/build/$f" | sed 's/^from "\.\///; s/"$//')
  pending+=("${deps[@]}")
done
# The page, its marker line replaced by the modulepreload links (largest
# first: three.js's core is the longest download).
preload=(viewer.js three/build/three.core.js three/build/three.module.js
  three/examples/jsm/loaders/GLTFLoader.js three/examples/jsm/controls/OrbitControls.js
  three/examples/jsm/utils/BufferGeometryUtils.js three/examples/jsm/utils/SkeletonUtils.js
  three/examples/jsm/libs/meshopt_decoder.module.js "${tiles_js[@]}")
# A static import of viewer.js missing from the list fails the build.
while read -r spec; do
  case $spec in
    three) f=three/build/three.module.js ;;
    three/addons/*) f=three/examples/jsm/${spec#three/addons/} ;;
    3d-tiles-renderer) f=3d-tiles-renderer/build/index.three.js ;;
    *) f=${spec#./} ;;
  esac
  printf '%s\n' "${preload[@]}" | grep -qxF "$f" \
    || { echo "build-web: viewer.js imports $spec, which index.html does not preload (add it to build-web.sh's list)" >&2; exit 1; }
done < <(grep -oE "^import .* from '[^']+';" "$web/viewer/viewer.js" | sed -E "s/.* from '([^']+)';$/\1/")
marker='<!-- modulepreload:'
grep -q "^$marker" "$web/viewer/index.html" || { echo "build-web: web/viewer/index.html has no '$marker' line" >&2; exit 1; }
while IFS= read -r line || [ -n "$line" ]; do
  if [[ $line == "$marker"* ]]; then
    for f in "${preload[@]}"; do
      [ -f "$tmp/$f" ] || { echo "build-web: $f (preloaded by index.html) is not in the site" >&2; exit 1; }
      printf '<link rel="modulepreload" href="./%s">\n' "$f"
    done
  else
    printf '%s\n' "$line"
  fi
done < "$web/viewer/index.html" > "$tmp/index.html"
rm -rf "$out"
chmod 755 "$tmp"
mv "$tmp" "$out"
trap - EXIT
echo "build-web: viewer in $out" >&2
