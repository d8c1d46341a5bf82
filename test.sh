#!/usr/bin/env bash
# The project's test command (README "Two commands", .ci/run): the Rust workspace's tests, then
# the Python module's: a virtualenv in target/pyenv with maturin, NumPy, pytest, meshio and Ray
# (installed once), the `starkrs` extension built in release mode into it, and its pytest suite;
# then, if a Chromium is installed, the HTML viewer in a headless browser.
set -euo pipefail
cd "$(dirname "$0")"

cargo test --workspace --release

python_start=$SECONDS
venv="$PWD/target/pyenv"
if [ ! -x "$venv/bin/python" ]; then
    "${PYTHON:-python3}" -m venv "$venv"
fi
if [ ! -x "$venv/bin/maturin" ] || ! "$venv/bin/python" -c "import numpy, pytest, meshio, ray" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "maturin>=1.8,<2" "numpy>=1.21" "pytest>=7" "meshio>=5" "ray>=2.9"
fi
VIRTUAL_ENV="$venv" "$venv/bin/maturin" develop --release --quiet -m crates/stark-python/Cargo.toml
"$venv/bin/python" -m pytest -q crates/stark-python/tests
echo "Python part (set-up, extension build, pytest): $((SECONDS - python_start)) s"

# The HTML viewer in a headless browser, when one is installed (Debian: apt-get install chromium):
# a short run, `stark view`, a screenshot, and a check that the scene's objects are in it.
browser="$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)"
if [ -n "$browser" ]; then
    "$venv/bin/python" crates/stark-cli/tests/viewer_screenshot.py "$browser" target/release/stark
else
    echo "viewer test skipped: no chromium found (it runs when one is installed)"
fi
