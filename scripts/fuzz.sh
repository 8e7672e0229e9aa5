#!/usr/bin/env bash
# Runs every lodkit fuzz target for MINUTES minutes each (default 5), then
# minimises each target's corpus to a set that keeps every coverage edge,
# the way crates/mesh/fuzz/README.md describes. Prints one line per target
# (runs, corpus size before and after, crash or not) for the READMEs' tables.
#
# Usage: scripts/fuzz.sh [MINUTES] [TARGET...]
#   TARGET: crate/target, e.g. mesh/ply, particles/pop, mco/mco_v2
#   (default: every target of crates/{mesh,particles,mco}/fuzz).
#
# Needs nightly and cargo-fuzz (`cargo install cargo-fuzz`). Runs under
# `nice -n 19` (FUZZ_NICE=N for another niceness: at 19 a fuzzer beside a
# build gets almost no CPU) with one job, so it can share a machine. Crashes are kept in
# crates/<crate>/fuzz/artifacts/<target>/ (ignored by git) and make the
# script exit 1 once every target has run.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
minutes=${1:-5}
shift || true
if ! [[ $minutes =~ ^[0-9]+$ ]] || [ "$minutes" -lt 1 ]; then
    echo "usage: scripts/fuzz.sh [MINUTES] [crate/target...]  (MINUTES: a whole number >= 1)" >&2
    exit 2
fi
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    echo "scripts/fuzz.sh: cargo-fuzz is missing: cargo install cargo-fuzz" >&2
    exit 2
fi

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    for crate in mesh particles mco; do
        dir="$root/crates/$crate/fuzz/fuzz_targets"
        [ -d "$dir" ] || continue
        for f in "$dir"/*.rs; do
            targets+=("$crate/$(basename "$f" .rs)")
        done
    done
fi

triple=$(rustc +nightly -vV | sed -n 's/^host: //p')
failed=0
for t in "${targets[@]}"; do
    crate=${t%%/*}
    name=${t#*/}
    fuzz="$root/crates/$crate/fuzz"
    corpus="$fuzz/corpus/$name"
    mkdir -p "$corpus"
    before=$(find "$corpus" -type f | wc -l)
    log="$fuzz/fuzz-$name.log"
    cd "$fuzz"
    status=ok
    # -O: release with debug assertions; one process (no -jobs, which would
    # log to fuzz-N.log instead), RSS and malloc capped at
    # libFuzzer's default 2 GB so a runaway allocation is a finding.
    # fuzz/seeds/<target>/ (valid files the crate's tests load) is read as
    # a second corpus and never written to or minimised.
    seeds=()
    [ -d "$fuzz/seeds/$name" ] && seeds=("$fuzz/seeds/$name")
    if ! nice -n "${FUZZ_NICE:-19}" cargo +nightly fuzz run -O "$name" "$corpus" "${seeds[@]}" -- \
        -max_total_time=$((minutes * 60)) -rss_limit_mb=2048 \
        -malloc_limit_mb=2048 -print_final_stats=1 >"$log" 2>&1; then
        status="CRASH (see $log and artifacts/$name/)"
        failed=1
    fi
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    # Minimise: keep a set of inputs that covers every edge (hit counts
    # ignored, or the glTF corpus keeps thousands of files).
    bin="$fuzz/target/$triple/release/$name"
    if [ -x "$bin" ]; then
        min=$(mktemp -d)
        if nice -n 19 "$bin" -set_cover_merge=1 -use_counters=0 "$min" "$corpus" \
            >>"$log" 2>&1; then
            find "$corpus" -type f -delete
            find "$min" -type f -exec mv {} "$corpus/" \;
        fi
        rm -rf "$min"
    fi
    after=$(find "$corpus" -type f | wc -l)
    echo "$t: ${minutes} min, ${runs:-?} runs, $status, corpus $before -> $after files"
done
exit $failed
