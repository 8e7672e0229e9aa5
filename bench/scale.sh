#!/usr/bin/env bash
# Out-of-core growth benchmark: for each size, a blob streamed
# to binary PLY (`lodkit generate blob`), then `lodkit simplify --ratio R`
# under /usr/bin/time, with the phases, bytes and rounds of its --json
# report; one table row per size, with time per input triangle and the
# ratio of each row's to the first row's.
#
# Usage: bench/scale.sh DIR [SIZES] [RATIO] [-- extra simplify options]
#   DIR    where the blobs and outputs go (needs 56 B of disk per triangle
#          of the largest size: 19 B the PLY, 36 B the staged blocks)
#   SIZES  comma-separated triangle counts (default 10000000,100000000,1000000000)
#   RATIO  default 0.01
# e.g. bench/scale.sh /big 10000000,100000000,1000000000 0.01 -- --memory 8G
# LODKIT=path/to/lodkit (default target/release/lodkit). Blobs already in
# DIR are reused. Drops the page cache before each run when it can (root),
# so reads come from disk.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:?usage: bench/scale.sh DIR [SIZES] [RATIO] [-- simplify options]}
shift
sizes=10000000,100000000,1000000000
ratio=0.01
if [ $# -gt 0 ] && [ "$1" != "--" ]; then sizes=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" != "--" ]; then ratio=$1; shift; fi
[ "${1:-}" = "--" ] && shift
lodkit=${LODKIT:-$root/target/release/lodkit}
mkdir -p "$dir"

echo "| input triangles | wall (s) | ns / triangle | vs first | peak RSS | phases (s) | rounds | read / written |"
echo "|---:|---:|---:|---:|---:|---|---|---|"
first=
for n in ${sizes//,/ }; do
    ply="$dir/blob$n.ply"
    [ -f "$ply" ] || "$lodkit" -q generate blob --triangles "$n" -o "$ply"
    out="$dir/out$n.ply"
    sync
    [ -w /proc/sys/vm/drop_caches ] && echo 3 >/proc/sys/vm/drop_caches || true
    /usr/bin/time -f "%e %M" -o "$dir/time$n" "$lodkit" -q simplify "$ply" -o "$out" \
        --ratio "$ratio" --json "$@" >"$dir/report$n.json"
    read -r wall rss_kb <"$dir/time$n"
    python3 - "$dir/report$n.json" "$wall" "$rss_kb" "${first:-}" <<'EOF'
import json, sys
rep = json.load(open(sys.argv[1]))
wall, rss_kb = float(sys.argv[2]), int(sys.argv[3])
n = rep["input_triangles"]
ns = wall * 1e9 / n
first = float(sys.argv[4]) if sys.argv[4] else ns
ooc = rep.get("out_of_core")
if ooc:
    phases = ", ".join("%s %.1f" % (p, s) for p, s in ooc["phases"])
    rounds = " + ".join(str(b) for b in ooc["round_blocks"]) + " blocks"
    io = "%.1f / %.1f GB" % (ooc["bytes_read"] / 1e9, ooc["bytes_written"] / 1e9)
else:
    phases, rounds, io = "in core %.1f" % rep["seconds"], "—", "—"
print("| %s | %.1f | %.0f | %.2f | %.2f GB | %s | %s | %s |"
      % (f"{n:,}", wall, ns, ns / first, rss_kb * 1024 / 1e9, phases, rounds, io))
open(sys.argv[1] + ".ns", "w").write("%f" % ns)
EOF
    [ -n "$first" ] || first=$(cat "$dir/report$n.json.ns")
done
