#!/usr/bin/env bash
# The project's test command (README "Two commands", .ci/run): the Rust workspace's tests, then
# the Python module's: a virtualenv in target/pyenv with maturin, NumPy and pytest (installed
# once), the `starkrs` extension built in release mode into it, and its pytest suite.
set -euo pipefail
cd "$(dirname "$0")"

cargo test --workspace --release

python_start=$SECONDS
venv="$PWD/target/pyenv"
if [ ! -x "$venv/bin/python" ]; then
    "${PYTHON:-python3}" -m venv "$venv"
fi
if [ ! -x "$venv/bin/maturin" ] || ! "$venv/bin/python" -c "import numpy, pytest" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "maturin>=1.8,<2" "numpy>=1.21" "pytest>=7"
fi
VIRTUAL_ENV="$venv" "$venv/bin/maturin" develop --release --quiet -m crates/stark-python/Cargo.toml
"$venv/bin/python" -m pytest -q crates/stark-python/tests
echo "Python part (set-up, extension build, pytest): $((SECONDS - python_start)) s"
