#!/usr/bin/env bash
# Digests of every output of the main commands on the shipped data, so a
# refactor can show that it changed no byte. Usage:
#   scripts/output_digests.sh [LODKIT_BINARY]            # print the digests
#   scripts/output_digests.sh --check [LODKIT_BINARY]    # compare with scripts/output_digests.txt
# `lods.json` and `report.html` hold wall times: they are stripped before hashing,
# and so are their sizes in the build's manifest.
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
bin=${1:-target/release/lodkit}
work=$(mktemp -d)
sums=$(mktemp)
trap 'rm -rf "$work" "$sums"' EXIT
bunny=data/models/stanford_bunny.ply
run() { "$bin" -q "$@" >/dev/null; }
run build --out "$work/build" --samples 100000
run simplify "$bunny" -o "$work/simplify_10.ply" --ratio 0.1
run simplify "$bunny" -o "$work/simplify_1k.glb" --target 1000
run scan "$bunny" --out "$work/scans"
run mco build "$work/scans/stanford_bunny.conf" -o "$work/bunny_scans.mco"
run mco build "$bunny" -o "$work/bunny_mesh.mco"
run mco extract "$work/bunny_mesh.mco" -o "$work/mco_10k.ply" --triangles 10000
run pop encode "$bunny" -o "$work/bunny.pop"
run pop decode "$work/bunny.pop" -o "$work/pop_l6.ply" --level 6
(
  cd "$work"
  find . -type f | LC_ALL=C sort | while read -r f; do
    case "$f" in
      */lods.json) python3 -c 'import json,sys
d=json.load(open(sys.argv[1]))
def strip(o):
    if isinstance(o, dict): return {k: strip(v) for k, v in o.items() if "seconds" not in k and "time" not in k and not k.endswith("_ms")}
    if isinstance(o, list): return [strip(v) for v in o]
    return o
print(json.dumps(strip(d), sort_keys=True))' "$f" | sha256sum | sed "s|-|$f (times stripped)|" ;;
      */.lodkit-build.json) python3 -c 'import json,sys
d=json.load(open(sys.argv[1]))
for k in ("report.html", "lods/lods.json"):
    d["files"].pop(k, None)
print(json.dumps(d, sort_keys=True))' "$f" | sha256sum | sed "s|-|$f (sizes of timed files stripped)|" ;;
      */report.html) sed '/<!-- varies -->/,/<!-- \/varies -->/d' "$f" | sha256sum | sed "s|-|$f (timings stripped)|" ;;
      *) sha256sum "$f" ;;
    esac
  done
) > "$sums"
if [ $check = 1 ]; then
  if diff -u scripts/output_digests.txt "$sums"; then echo "output digests: all identical"; else echo "output digests differ"; exit 1; fi
else
  cat "$sums"
fi
