#!/usr/bin/env bash
# GLBs lodkit writes, checked by real glTF loaders in Node (tests/gltf/):
# the Khronos glTF-Validator on every file (0 errors, 0 warnings, no
# UNUSED_OBJECT on a UV attribute), Babylon.js (NullEngine) on the LOD
# chains (it implements MSFT_lod: every level seen, coarsest first, in
# place; for scene chains, every level and then level 0's meshes alone),
# three.js GLTFLoader on every file (no MSFT_lod: level 0 alone).
#
# Usage: scripts/check-gltf.sh [LODKIT_BINARY]
# Without a binary it builds target/release/lodkit with `--features
# compress` (meshoptimizer, C++), since the compressed files are checked
# too. Needs node >= 18 and npm; installs tests/gltf/ with `npm ci`.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ge 1 ]; then
  bin=$1
else
  LODKIT_VIEWER=${LODKIT_VIEWER:-skip} cargo build --release -q -p lodkit-cli --features compress
  bin=target/release/lodkit
fi
bin=$(realpath "$bin")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

(cd tests/gltf && npm ci --no-audit --no-fund --loglevel=error >/dev/null)

bunny=data/models/stanford_bunny.ply
run() { "$bin" -q "$@" >/dev/null; }
# A cube without normals (auto normals split it at its 90-degree edges), a
# point cloud with normals and colours in XYZ and PLY.
cat > "$work/cube.obj" <<'EOF'
v 0 0 0
v 1 0 0
v 0 1 0
v 1 1 0
v 0 0 1
v 1 0 1
v 0 1 1
v 1 1 1
f 1 3 4
f 1 4 2
f 5 6 8
f 5 8 7
f 1 2 6
f 1 6 5
f 3 7 8
f 3 8 4
f 1 5 7
f 1 7 3
f 2 4 8
f 2 8 6
EOF
python3 - "$work" <<'EOF'
import math, sys
d = sys.argv[1]
with open(f"{d}/cloud.xyz", "w") as f:
    for i in range(2000):
        t, p = math.acos(1 - 2 * (i + 0.5) / 2000), i * 2.399963
        n = (math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t))
        f.write("%.6f %.6f %.6f %.6f %.6f %.6f\n" % (n + n))
with open(f"{d}/cloud.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
    for i in range(1000):
        f.write("%d %d %d %d %d %d\n" % (i % 10, (i // 10) % 10, i // 100, 25 * (i % 10), 25 * ((i // 10) % 10), 25 * (i // 100)))
EOF

run lods "$bunny" --out "$work/lods" --samples 20000
run lods "$bunny" --out "$work/lods_c" --samples 20000 --compress
run lods "$work/cube.obj" --out "$work/lods_cube" --levels 2 --normals auto=30
run build --out "$work/build" --levels 3 --no-measure
run convert "$bunny" "$work/convert.glb"
run convert "$bunny" "$work/convert_c.glb" --compress
run convert "$work/cube.obj" "$work/cube.glb"
run convert "$work/cloud.xyz" "$work/points_xyz.glb"
run convert "$work/cloud.ply" "$work/points_ply.glb"
run convert "$work/cloud.xyz" "$work/points_c.glb" --compress
run simplify "$bunny" -o "$work/simplify.glb" --ratio 0.1
run simplify "$bunny" -o "$work/simplify_c.glb" --ratio 0.1 --compress --normals none
# Scenes with materials and textures (crates/mesh/tests/data/textured):
# external PNG + JPEG, a shared material, nested nodes, a textured scan.
tex=crates/mesh/tests/data/textured
run convert "$tex/parts.obj" "$work/parts_obj.glb"
run convert "$tex/parts.gltf" "$work/parts_gltf.glb"
run simplify "$tex/parts.gltf" -o "$work/parts_simplified.glb" --ratio 0.5
run simplify "$tex/mug_scan.ply" -o "$work/mug_10.glb" --ratio 0.1
run lods "$tex/mug_scan.ply" --out "$work/lods_mug" --ratios 0.5,0.1 --samples 20000
run lods "$tex/parts.gltf" --out "$work/lods_parts" --ratios 0.5,0.2 --samples 20000
run lods "$tex/parts.obj" --out "$work/lods_parts_c" --ratios 0.5,0.2 --samples 20000 --compress
run convert "$tex/parts.gltf" "$work/parts_c.glb" --compress
run simplify "$tex/mug_scan.ply" -o "$work/mug_10_c.glb" --ratio 0.1 --compress
# build keeps a scene's materials in its GLB and its HQMS chain (and its tileset).
run build "$tex/parts.gltf" --out "$work/build_parts" --levels 2 --no-measure
# Textured tiles: each tile's texture cropped to its UVs (PNG, and JPEG
# for parts' JPEG texture), compressed too.
run tiles "$tex/mug_scan.obj" --out "$work/tiles_mug" --leaf-triangles 256
run tiles "$tex/parts.gltf" --out "$work/tiles_parts" --leaf-triangles 64
run tiles "$tex/parts.obj" --out "$work/tiles_parts_c" --leaf-triangles 64 --compress
# Tile contents on one quantisation grid shared by several files
# (io::gltf::write_*_on_grid: two neighbouring mesh tiles and a POINTS
# tile, plain and compressed), written by the mesh crate's test.
LODKIT_GLB_OUT="$work/grid" cargo test -q -p lodkit-mesh --features meshopt --test gltf_grid >/dev/null
for f in "$work"/grid/*.glb; do "$bin" -q info "$f" >/dev/null; done
# lodkit reads back what it wrote (compressed and points included).
for f in convert_c simplify_c points_xyz points_c parts_c mug_10_c lods_parts_c/parts_lods; do
  "$bin" -q info "$work/$f.glb" >/dev/null
done

mapfile -t glbs < <(find "$work" -name '*.glb' | LC_ALL=C sort)
check=tests/gltf/check.mjs
node "$check" validate "${glbs[@]}"
node "$check" load "${glbs[@]}"
node "$check" chain "$work/lods/stanford_bunny_lods.glb" 7
node "$check" chain "$work/lods_c/stanford_bunny_lods.glb" 7
node "$check" chain "$work/build/lods/stanford_bunny_lods.glb" 4
# Scene chains: a root node per level over that level's meshes.
node "$check" scenechain "$work/lods_mug/mug_scan_lods.glb" 3
node "$check" scenechain "$work/lods_parts/parts_lods.glb" 3
node "$check" scenechain "$work/lods_parts_c/parts_lods.glb" 3
node "$check" scenechain "$work/build_parts/lods/parts_lods.glb" 3
echo "glTF checks: ${#glbs[@]} GLBs valid; LOD chains seen by Babylon.js and three.js"
