#!/usr/bin/env bash
# The project's single test command: Rust tests, the Python reference oracle's own tests, and the
# quick foundation benchmark. Run from anywhere; extra arguments go to `cargo test`.
#
#   tests/run_all.sh                 # everything
#   tests/run_all.sh --test io       # cargo test --release --test io, then the rest
#
# The oracle venv (reference/.venv) is created on first use and rebuilt whenever
# reference/requirements.txt changes (its sha256 is stamped inside the venv).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT="$(pwd)"
VENV="$ROOT/reference/.venv"
REQ="$ROOT/reference/requirements.txt"
STAMP="$VENV/.requirements.sha256"

step() { printf '\n==== %s\n' "$*"; }

step "[1/4] Python oracle venv (reference/.venv)"
want="$(sha256sum "$REQ" | cut -d' ' -f1)"
have="$(cat "$STAMP" 2>/dev/null || true)"
if [[ ! -x "$VENV/bin/python" || "$want" != "$have" ]]; then
    echo "creating reference/.venv and installing reference/requirements.txt"
    start=$SECONDS
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check -r "$REQ"
    echo "$want" >"$STAMP"
    echo "venv ready in $((SECONDS - start)) s"
else
    echo "up to date"
fi
export VESSELMSR_PYTHON="$VENV/bin/python"

step "[2/4] cargo test --release $*"
cargo test --release "$@"

step "[3/4] pytest reference (oracle self-tests)"
"$VESSELMSR_PYTHON" -m pytest -q reference

step "[4/4] cargo bench --bench foundation (quick benchmark)"
# A quick benchmark binary; skipped while benches/foundation.rs does not exist.
if [[ -f benches/foundation.rs ]]; then cargo bench --bench foundation; else echo "skipped: no benches/foundation.rs"; fi

echo
echo "run_all: all steps passed"
