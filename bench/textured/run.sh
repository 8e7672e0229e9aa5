#!/usr/bin/env bash
# Texture-aware quality bench (docs/benchmarks.md, "Textured scans"):
# lodkit, gltfpack and MeshLab's texture-aware quadric decimation on the
# same textured inputs at 50 / 10 / 1 %, one run. Per output: geometric
# error (`lodkit compare`, symmetric Hausdorff and mean, % of the input's
# bbox diagonal) and texture-space error (bench/textured/texerr.py: UV
# displacement in texels, RGB error of the textured surface).
#
# usage: bench/textured/run.sh [LODKIT] [WORKDIR]
# Installs gltfpack (npm) and pymeshlab, numpy, Pillow (pip, a venv) under
# WORKDIR (default target/bench-textured). Inputs: the textured mug scan of
# crates/mesh/tests/data/textured, and a 4x denser crop of the same scan
# when ../shared/data/range/pcl is there (made by its make.py).
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=$(realpath "${1:-target/release/lodkit}")
work=$(mkdir -p "${2:-target/bench-textured}" && realpath "${2:-target/bench-textured}")
py=$work/venv/bin/python
[ -x "$py" ] || { python3 -m venv "$work/venv"; "$work/venv/bin/pip" -q install pymeshlab numpy pillow; }
[ -x "$work/npm/node_modules/.bin/gltfpack" ] || { mkdir -p "$work/npm"; (cd "$work/npm" && npm init -y >/dev/null && npm install -s gltfpack >/dev/null); }
gltfpack=$work/npm/node_modules/.bin/gltfpack
data=crates/mesh/tests/data/textured
inputs=$work/inputs
mkdir -p "$inputs"
cp $data/mug_scan.obj $data/mug_scan.mtl $data/mug_scan.png "$inputs/"
echo "input faces ratio tool seconds hausdorff_pct mean_pct uv_texels_mean uv_texels_p95 color_rmse"
for name in mug_scan; do
  in=$inputs/$name.obj
  faces=$(grep -c '^f ' "$in")
  diag=$("$bin" -q info "$in" --json | "$py" -c 'import json,sys; print(json.load(sys.stdin)["bbox"]["diagonal"])' 2>/dev/null || echo 1)
  "$bin" -q convert "$in" "$inputs/$name.glb"
  for r in 0.5 0.1 0.01; do
    out=$work/out/$name/$r
    mkdir -p "$out"
    target=$("$py" -c "print(max(1, int($faces * $r)))")
    t0=$(date +%s.%N)
    "$bin" -q simplify "$in" -o "$out/lodkit.obj" --ratio "$r"
    t1=$(date +%s.%N)
    "$gltfpack" -i "$inputs/$name.glb" -o "$out/gltfpack.glb" -si "$r" -noq >/dev/null 2>&1
    t2=$(date +%s.%N)
    "$bin" -q convert "$out/gltfpack.glb" "$out/gltfpack.obj"
    t3=$(date +%s.%N)
    "$py" - "$in" "$out/meshlab.obj" "$target" <<'PY'
import sys, pymeshlab
ms = pymeshlab.MeshSet()
ms.load_new_mesh(sys.argv[1])
ms.meshing_decimation_quadric_edge_collapse_with_texture(targetfacenum=int(sys.argv[3]))
ms.save_current_mesh(sys.argv[2])
PY
    t4=$(date +%s.%N)
    for tool in lodkit gltfpack meshlab; do
      case $tool in
        lodkit) secs=$("$py" -c "print(f'{$t1 - $t0:.3f}')") ;;
        gltfpack) secs=$("$py" -c "print(f'{$t2 - $t1:.3f}')") ;;
        meshlab) secs=$("$py" -c "print(f'{$t4 - $t3:.3f}')") ;;
      esac
      geo=$("$bin" -q compare "$in" "$out/$tool.obj" --samples 200000 --json | "$py" -c "
import json,sys; d=json.load(sys.stdin); s=d['symmetric']; print(f\"{100*s['max']/$diag:.3f} {100*s['mean']/$diag:.4f}\")")
      tex=$("$py" bench/textured/texerr.py "$in" "$out/$tool.obj" 20000 | "$py" -c "
import json,sys; d=json.load(sys.stdin); print(d['faces'], f\"{d['uv_texels_mean']:.3f} {d['uv_texels_p95']:.3f} {d['color_rmse']:.2f}\")")
      set -- $tex
      echo "$name $1 $r $tool $secs $geo $2 $3 $4"
    done
  done
done
