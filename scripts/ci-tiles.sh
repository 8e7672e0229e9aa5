#!/usr/bin/env bash
# 3D Tiles tilesets in their clients (called by .ci/run), on small inputs:
#   1. every tileset walked (tileset.json and its external tilesets) and
#      every tile through the Khronos glTF-Validator
#      (web/tests/tiles/check_tileset.mjs);
#   2. in headless Chromium (Debian's, driven by playwright-core): lodkit's
#      viewer (3DTilesRendererJS) and CesiumJS load each tileset with no
#      console error and show the model (web/tests/tiles.test.mjs);
#   3. `lodkit serve` lists the tilesets and its viewer opens them.
# The tilesets: `lodkit tiles` of the shipped bunny when the binary has that
# command, else a fixture made from GLBs lodkit writes
# (web/tests/make_fixture_tileset.mjs: plain and meshopt-compressed).
#
# Usage: scripts/ci-tiles.sh [DIR REL/tileset.json...]   (tilesets of your own)
# Environment: LODKIT (the binary; default target/release/lodkit, built
# if missing). Installs chromium and npm with apt-get when missing, and the
# npm packages of web/ and web/tests/tiles/ with `npm ci`.
# Output (screenshots, results.json): target/web-test/tiles/.
# CesiumGS's 3d-tiles-validator runs when LODKIT_3DTILES_VALIDATOR names a
# built checkout of it (its `build/main.js`): npm has no `3d-tiles-validator`
# package (it is published from its GitHub repository only), so CI without
# one says so in one line.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
work=$root/target/web-test/tiles
mkdir -p "$work"
start=$(date +%s)

missing=()
[ -x /usr/bin/chromium ] || missing+=(chromium)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then
  echo "== apt-get install ${missing[*]}"
  sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi

lodkit=${LODKIT:-$root/target/release/lodkit}
if [ ! -x "$lodkit" ]; then
  echo "== release binary"
  cargo build --release --quiet -p lodkit-cli
fi
echo "== the viewer and the npm packages"
scripts/build-web.sh "$work/site"
npm_ci() { (cd "$1" && { [ -f node_modules/.package-lock.json ] && [ node_modules/.package-lock.json -nt package-lock.json ] || npm ci --no-audit --no-fund --ignore-scripts --loglevel=error; }); }
npm_ci web
npm_ci web/tests/tiles

if [ $# -ge 2 ]; then
  sets_dir=$(realpath "$1")
  shift
  sets=("$@")
elif "$lodkit" tiles --help >/dev/null 2>&1; then
  echo "== tilesets: lodkit tiles of the shipped bunny and of the scans in ../shared/data"
  sets_dir=$work/sets
  rm -rf "$sets_dir"
  mkdir -p "$sets_dir"
  "$lodkit" -q tiles data/models/stanford_bunny.ply --out "$sets_dir/bunny"
  sets=(bunny/tileset.json)
  shared=${LODKIT_SHARED_DATA:-$root/../shared/data}
  for pair in closed_bunny:meshes/stanford_bunny_closed_glmark2.ply mug_rgbd:textured/table_scene_mug_rgbd.obj \
    lms400:points/table_scene_lms400.ply autzen:points/autzen_trim.laz; do
    name=${pair%%:*} input=$shared/${pair#*:}
    if [ -f "$input" ]; then
      "$lodkit" -q tiles "$input" --out "$sets_dir/$name"
      sets+=("$name/tileset.json")
    else
      echo "skipped $name: $input is absent"
    fi
  done
else
  echo "== tilesets: the fixture (lodkit has no tiles command)"
  sets_dir=$work/sets
  node web/tests/make_fixture_tileset.mjs "$lodkit" "$sets_dir"
  sets=(plain/tileset.json meshopt/tileset.json points/tileset.json)
fi

status=0
echo "== every tile through glTF-Validator"
node web/tests/tiles/check_tileset.mjs "${sets[@]/#/$sets_dir/}" || status=1

validator=${LODKIT_3DTILES_VALIDATOR:-}
if [ -n "$validator" ] && [ -f "$validator/build/main.js" ]; then
  echo "== every tileset through CesiumGS's 3d-tiles-validator"
  for s in "${sets[@]}"; do
    report=$(node "$validator/build/main.js" --tilesetFile "$sets_dir/$s" 2>&1 || true)
    if printf '%s' "$report" | grep -q '"numErrors": 0,' && printf '%s' "$report" | grep -q '"numWarnings": 0,'; then
      echo "ok   3d-tiles-validator: $s ($(printf '%s' "$report" | grep -o '"numInfos": [0-9]*'))"
    else
      echo "FAIL 3d-tiles-validator: $s"
      printf '%s\n' "$report" | head -40
      status=1
    fi
  done
else
  echo "skipped 3d-tiles-validator: not on npm; set LODKIT_3DTILES_VALIDATOR to a built checkout of CesiumGS/3d-tiles-validator"
fi

echo "== Chromium: the viewer (3DTilesRendererJS) and CesiumJS"
LODKIT_WEB_SITE=$work/site LODKIT_WEB_OUT=$work/static node web/tests/tiles.test.mjs "$sets_dir" "${sets[@]}" || status=1

echo "== lodkit serve: tilesets listed, opened by its viewer"
port=$(node -e 'const s=require("net").createServer().listen(0,"127.0.0.1",()=>{console.log(s.address().port);s.close()})')
"$lodkit" serve "$sets_dir" --port "$port" --exit-after 600 > "$work/serve.log" 2>&1 &
serve_pid=$!
trap 'kill $serve_pid 2>/dev/null || true' EXIT
for _ in $(seq 100); do node -e 'require("http").get(process.argv[1],r=>process.exit(0)).on("error",()=>process.exit(1))' "http://127.0.0.1:$port/" && break; sleep 0.1; done
node -e '
const [base, ...want] = process.argv.slice(1);
fetch(base + "/api/models").then((r) => r.json()).then((list) => {
  const sets = list.filter((e) => e.kind === "tileset").map((e) => e.name).sort();
  if (JSON.stringify(sets) !== JSON.stringify([...want].sort())) {
    console.error(`FAIL lodkit serve lists tilesets ${JSON.stringify(sets)}, expected ${JSON.stringify(want)}`);
    process.exit(1);
  }
  console.log(`ok   lodkit serve lists ${sets.length} tileset(s) among ${list.length} files`);
});
' "http://127.0.0.1:$port" "${sets[@]}" || status=1
LODKIT_TILES_CLIENTS=viewer LODKIT_WEB_BASE=http://127.0.0.1:$port LODKIT_WEB_SITE=$work/site LODKIT_WEB_OUT=$work/serve \
  node web/tests/tiles.test.mjs "$sets_dir" "${sets[@]}" || status=1
kill $serve_pid 2>/dev/null || true
wait $serve_pid 2>/dev/null || true

echo "== tiles step: $(( $(date +%s) - start )) s"
exit $status
