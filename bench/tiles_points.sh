#!/usr/bin/env bash
# Point tilesets out of core: for each size, a noisy coloured sphere
# written as binary PLY (crates/tiles/examples/noisy_cloud.rs, 15 B a
# point, deterministic), then `lodkit tiles CLOUD --memory M` under
# /usr/bin/time; one row per size: the load average before it, wall and
# CPU seconds, points per second (wall and CPU), peak RSS. The passes,
# subtrees and writes use every core (RAYON_NUM_THREADS=N for fewer). With CHECK=1, also tiles each cloud in core
# and says whether the two folders hold the same bytes.
#
# Usage: bench/tiles_points.sh DIR [SIZES] [MEMORY]
#   DIR     where clouds and tilesets go (about 30 B of disk per point of
#           the largest size while it runs; outputs removed after each row)
#   SIZES   comma-separated point counts (default 10000000)
#   MEMORY  the --memory budget (default 128M)
# LODKIT=path/to/lodkit (default target/release/lodkit; built if absent).
# Clouds already in DIR are reused; remove DIR when done.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:?usage: bench/tiles_points.sh DIR [SIZES] [MEMORY]}
sizes=${2:-10000000}
memory=${3:-128M}
lodkit=${LODKIT:-$root/target/release/lodkit}
[ -x "$lodkit" ] || cargo build --release -q -p lodkit-cli --manifest-path "$root/Cargo.toml"
gen=$root/target/release/examples/noisy_cloud
[ -x "$gen" ] || cargo build --release -q -p lodkit-tiles --example noisy_cloud --manifest-path "$root/Cargo.toml"
mkdir -p "$dir"

echo "| points | --memory | load | wall (s) | CPU (s) | M points/s (wall) | M points/s (CPU) | peak RSS | same bytes as in core |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|---|"
for n in ${sizes//,/ }; do
    ply="$dir/cloud$n.ply"
    [ -f "$ply" ] || "$gen" "$n" "$ply"
    out="$dir/ooc$n"
    rm -rf "$out"
    read -r load _ </proc/loadavg
    /usr/bin/time -f "%e %U %S %M" -o "$dir/time$n" "$lodkit" -q tiles "$ply" --out "$out" --memory "$memory"
    read -r wall user sys rss_kb <"$dir/time$n"
    same=-
    if [ "${CHECK:-0}" = 1 ]; then
        rm -rf "$dir/in$n"
        "$lodkit" -q tiles "$ply" --out "$dir/in$n" --memory 1P
        if diff -r -q "$out" "$dir/in$n" >/dev/null; then same=yes; else same=NO; fi
        rm -rf "$dir/in$n"
    fi
    rm -rf "$out"
    awk -v n="$n" -v m="$memory" -v l="$load" -v w="$wall" -v u="$user" -v s="$sys" -v r="$rss_kb" -v same="$same" 'BEGIN {
        cpu = u + s
        printf "| %d | %s | %s | %.2f | %.2f | %.2f | %.2f | %.0f MiB | %s |\n", n, m, l, w, cpu, n / w / 1e6, n / cpu / 1e6, r / 1024, same
    }'
done
