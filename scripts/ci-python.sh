#!/usr/bin/env bash
# The Python package's CI: builds the pylodkit wheel (maturin, abi3) in a
# virtual environment it makes, installs it, and runs the pytest suite in
# python/tests (numpy API, errors, mco/pop, trimesh and open3d round trips,
# a small Ray batch with a broken asset and a resume, `lodkit simplify
# --ray local` against the single-process bytes).
#
# Needs: python3 >= 3.9 with venv, cargo; PyPI reachable. open3d is tried
# and its tests skip where it does not install. Takes ~4-6 minutes on the
# 2-core machine (most of it the wheel's release build and `pip install ray`).
#
# Usage: scripts/ci-python.sh            (venv in target/python-ci/venv)
#        LODKIT_PY_VENV=DIR scripts/ci-python.sh
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
export LODKIT_VIEWER=skip
venv=${LODKIT_PY_VENV:-$root/target/python-ci/venv}
py=${PYTHON:-python3}

if [ ! -x "$venv/bin/python" ]; then
    "$py" -m venv "$venv"
fi
vpy="$venv/bin/python"
"$vpy" -m pip install -q --disable-pip-version-check --upgrade pip
"$vpy" -m pip install -q --disable-pip-version-check "maturin>=1.7,<2" numpy pytest ray trimesh
if ! "$vpy" -m pip install -q --disable-pip-version-check open3d; then
    echo "ci-python: open3d did not install; its round-trip test will skip"
fi

# The wheel: release profile (the tests run real simplifications), built
# into the workspace's target/ so cargo's cache is shared with the rest.
wheels="$root/target/python-ci/wheels"
rm -rf "$wheels"
(cd python && nice -n 10 "$venv/bin/maturin" build --release --quiet --out "$wheels" -i "$vpy")
"$vpy" -m pip install -q --disable-pip-version-check --force-reinstall --no-deps "$wheels"/pylodkit-*.whl

# The CLI, for the `lodkit simplify --ray` test (already built by the
# browser checks in .ci/run; a no-op then).
nice -n 10 cargo build --release --quiet -p lodkit-cli
export LODKIT_BIN="$root/target/release/lodkit"

# Run from outside the source tree so `import pylodkit` is the installed wheel.
cd "$root/target/python-ci"
"$vpy" -m pytest -q -p no:cacheprovider "$root/python/tests" "$@"
