#!/usr/bin/env bash
# The compressed LOD chain's size beside gltfpack's: lodkit's one
# `--compress` chain GLB (level 0 = the input, then the levels) against the
# sum of `gltfpack -cc` run on each of the same levels on its own (each
# level given to gltfpack as the uncompressed GLB lodkit writes for it, with
# the same normals). Prints one table; for docs/benchmarks.md.
#
# Usage: scripts/gltfpack-size.sh [LODKIT_BINARY] [INPUT]   (default: the bunny)
# Needs a lodkit built with `--features compress`, node and npm (installs
# tests/gltf/ with `npm ci`, which pins gltfpack).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=$(realpath "${1:-target/release/lodkit}")
input=${2:-data/models/stanford_bunny.ply}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd tests/gltf && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
gltfpack=tests/gltf/node_modules/gltfpack/cli.js
stem=$(basename "${input%.*}")
"$bin" -q lods "$input" --out "$work/plain" --samples 20000
"$bin" -q lods "$input" --out "$work/packed" --samples 20000 --compress
chain=$(stat -c %s "$work/packed/${stem}_lods.glb")
plain=$(stat -c %s "$work/plain/${stem}_lods.glb")
total=0
printf '| level | triangles | gltfpack -cc bytes |\n|---:|---:|---:|\n'
levels=("$input")
for f in "$work"/plain/"${stem}"_lod*.ply; do levels+=("$f"); done
for k in "${!levels[@]}"; do
  "$bin" -q convert "${levels[$k]}" "$work/level$k.glb"
  node "$gltfpack" -i "$work/level$k.glb" -o "$work/level${k}_cc.glb" -cc >/dev/null
  size=$(stat -c %s "$work/level${k}_cc.glb")
  tris=$("$bin" info --json "$work/level$k.glb" | python3 -c 'import json,sys; print(json.load(sys.stdin)["faces"])')
  total=$((total + size))
  printf '| %d | %d | %d |\n' "$k" "$tris" "$size"
done
printf '\ngltfpack -cc, each level on its own, sum: %d bytes\n' "$total"
printf 'lodkit lods --compress, one chain GLB:  %d bytes (uncompressed chain: %d)\n' "$chain" "$plain"
