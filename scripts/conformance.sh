#!/usr/bin/env bash
# The conformance suite (tests/conformance/run.py, called by .ci/run): the
# shipped bunny and every real scan of ../shared/data through build, mco
# build, pop encode, lods, convert and render, every output read back by
# the CLI, by pylodkit and by the wasm decoders under Node; detail, colours,
# cracks on closed inputs, byte-identical reruns.
#
# Needs: cargo, node, python3 with venv. Reuses the venv of
# scripts/ci-python.sh (target/python-ci/venv) when it holds pylodkit,
# else builds the wheel there the same way; adds Pillow (the pictures).
# Usage: scripts/conformance.sh [run.py options, e.g. --only bunny_closed]
#        LODKIT_SHARED_DATA=DIR to take the scans from elsewhere.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
start=$(date +%s)

echo "== release binary, native example, wasm decoders"
nice -n 10 cargo build --release --quiet -p lodkit-cli
nice -n 10 cargo build --release --quiet -p lodkit-wasm --example native
wasm=$root/target/web-wasm/wasm32-unknown-unknown/release/lodkit_wasm.wasm
CARGO_PROFILE_RELEASE_DEBUG=false CARGO_PROFILE_RELEASE_STRIP=true \
  nice -n 10 cargo build --release --quiet -p lodkit-wasm --target wasm32-unknown-unknown \
  --target-dir "$root/target/web-wasm"

venv=${LODKIT_PY_VENV:-$root/target/python-ci/venv}
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
fi
vpy="$venv/bin/python"
if ! "$vpy" -c 'import pylodkit' >/dev/null 2>&1 || [ "${LODKIT_REBUILD_WHEEL:-0}" = 1 ]; then
  echo "== pylodkit wheel"
  "$vpy" -m pip install -q --disable-pip-version-check "maturin>=1.7,<2" numpy
  wheels=$root/target/python-ci/wheels
  rm -rf "$wheels"
  (cd python && nice -n 10 "$venv/bin/maturin" build --release --quiet --out "$wheels" -i "$vpy")
  "$vpy" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$wheels"/pylodkit-*.whl
fi
"$vpy" -c 'import PIL' >/dev/null 2>&1 || "$vpy" -m pip install -q --disable-pip-version-check pillow

data=${LODKIT_SHARED_DATA:-$root/../shared/data}
echo "== conformance (data: $data)"
# From outside the source tree, so `import pylodkit` is the installed wheel.
cd "$root/target"
status=0
"$vpy" "$root/tests/conformance/run.py" --lodkit "$root/target/release/lodkit" \
  --native "$root/target/release/examples/native" --wasm "$wasm" --data "$data" "$@" || status=$?
echo "== conformance step: $(( $(date +%s) - start )) s"
exit $status
