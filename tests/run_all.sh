#!/usr/bin/env bash
# The project's test command (what CI runs): the Rust tests, the Python reference oracle's own
# tests, the Python package (python/: its wheel built by maturin, installed into the oracle
# venv, and its pytest), and a 60 s smoke run of every fuzz target at once (fuzz/smoke.sh), a few
# minutes from a warm build (the fuzz targets build beside steps 3 to 5). Run from anywhere;
# extra arguments go to `cargo test`. The integration tests are one binary, `suite`
# (tests/suite/main.rs), a module per file: tests/suite/io_formats.rs holds io_formats::*.
#
#   bash tests/run_all.sh                 # the quick suite
#   bash tests/run_all.sh --test suite io_formats::   # cargo test --profile ci --test suite
#                                         # io_formats:: (one file's tests), then the Python steps
#   bash tests/run_slow.sh                # the slow real-mesh studies only (= run_all.sh --slow)
#   VESSELMSR_FUZZ_SECONDS=10 bash tests/run_all.sh   # a shorter fuzz smoke (0 skips it);
#                                         # ignored when CI=true: CI always runs it for 60 s
#
# The slow studies are Rust tests in a module `slow` marked
# #[ignore = "slow: run by tests/run_slow.sh"] (bvh_closest::slow::…); the quick suite keeps a
# cheaper case of each.
# Benchmarks (cargo bench --bench NAME) are not tests and run apart (README).
#
# Tests that skip checks (no ../shared/data/real, no vtk in the venv) record a line in the file
# $VESSELMSR_SKIPPED (tests/suite/common/mod.rs `skip`), listed in the summary with the ignored
# tests.
# The oracle venv (reference/.venv) is created on first use and rebuilt whenever
# reference/requirements.txt changes (its sha256 is stamped inside the venv).
#
# The Rust steps build with the profile `ci` (release with incremental compilation, so a change
# to the library recompiles only what it touched; measured in Cargo.toml's comment on it).
# `cargo test --workspace` tests the root package only (python/ has no Rust tests) but resolves
# the dependencies' features together with python/'s, so the wheel's `maturin build --profile
# ci` (same target dir) reuses the compiled library and its dependencies: it compiles only the
# bindings (seconds) instead of the whole tree again.
set -euo pipefail

slow=false
if [[ "${1:-}" == "--slow" ]]; then
    slow=true
    shift
fi

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT="$(pwd)"
VENV="$ROOT/reference/.venv"
REQ="$ROOT/reference/requirements.txt"
STAMP="$VENV/.requirements.sha256"
if $slow; then steps=2; else steps=6; fi
fuzz_seconds="${VESSELMSR_FUZZ_SECONDS:-60}"
if [[ "${CI:-}" == true ]]; then
    fuzz_seconds=60
elif ! [[ "$fuzz_seconds" =~ ^(0|[1-9][0-9]*)$ ]]; then
    echo "run_all: VESSELMSR_FUZZ_SECONDS must be a number of seconds (0 skips the fuzz smoke)" >&2
    exit 2
fi

step() { printf '\n==== [%s/%s] %s\n' "$1" "$steps" "${*:2}"; }

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
export VESSELMSR_SKIPPED="$WORK/skipped"
: >"$VESSELMSR_SKIPPED"
LOG="$WORK/cargo-test.log"

step 1 "Python oracle venv (reference/.venv)"
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
# The CLI that the Python steps run (reference/test_vtk_formats.py, python/tests): the one step 2
# builds, in $CARGO_TARGET_DIR when that is set.
target_dir="${CARGO_TARGET_DIR:-target}"
[[ "$target_dir" == /* ]] || target_dir="$ROOT/$target_dir"
export VESSELMSR_BIN="${VESSELMSR_BIN:-$target_dir/ci/vesselmsr}"

rust_start=$SECONDS
if $slow; then
    # libtest runs the tests that match any one of its filters, so a filter of the caller's own (a
    # test path, with "::": msr_cortex::slow::) replaces slow:: instead of being added to it.
    filters=(slow::)
    for arg in "$@"; do
        if [[ "$arg" == *::* ]]; then filters=(); fi
    done
    step 2 "cargo test --profile ci $* -- --ignored ${filters[*]} (the slow real-mesh studies)"
    cargo_args=(--profile ci --workspace --no-fail-fast "$@" -- --ignored "${filters[@]}")
else
    step 2 "cargo test --profile ci $*"
    cargo_args=(--profile ci --workspace --no-fail-fast "$@")
fi
rust_status=0
cargo test "${cargo_args[@]}" 2>&1 | tee "$LOG" || rust_status=$?
rust_seconds=$((SECONDS - rust_start))

# The fuzz targets' build (its own workspace and target dir in fuzz/) runs under nice beside the
# Python steps below, which leave a core idle; step 6 then only runs the targets.
fuzz_build_pid=""
if ! $slow && [[ $fuzz_seconds -gt 0 ]]; then
    bash "$ROOT/fuzz/smoke.sh" --build-only >"$WORK/fuzz-build.log" 2>&1 &
    fuzz_build_pid=$!
fi

py_status=0
py_seconds=0
wheel_status=0
wheel_seconds=0
pkg_status=0
pkg_seconds=0
if ! $slow && [[ $rust_status -eq 0 ]]; then
    step 3 "pytest reference (oracle self-tests)"
    py_start=$SECONDS
    "$VESSELMSR_PYTHON" -m pytest -q reference || py_status=$?
    py_seconds=$((SECONDS - py_start))

    step 4 "Python package: maturin build --profile ci (python/), pip install into reference/.venv"
    wheel_start=$SECONDS
    {
        "$VENV/bin/maturin" build --profile ci --manifest-path "$ROOT/python/Cargo.toml" \
            --interpreter "$VESSELMSR_PYTHON" --out "$WORK/wheels" &&
            "$VESSELMSR_PYTHON" -m pip install --quiet --disable-pip-version-check \
                --force-reinstall --no-deps "$WORK"/wheels/vesselmsr-*.whl
    } || wheel_status=$?
    wheel_seconds=$((SECONDS - wheel_start))

    if [[ $wheel_status -eq 0 ]]; then
        step 5 "pytest python/tests (the Python package against the CLI, Dask cohort)"
        pkg_start=$SECONDS
        "$VESSELMSR_PYTHON" -m pytest -q python/tests || pkg_status=$?
        pkg_seconds=$((SECONDS - pkg_start))
    fi
fi

fuzz_status=0
fuzz_time="skipped"
if ! $slow; then
    # Independent of the steps above (its own workspace and build in fuzz/), so it runs whatever
    # they gave.
    if [[ $fuzz_seconds -gt 0 ]]; then
        step 6 "fuzz smoke: every fuzz target at once for $fuzz_seconds s (fuzz/smoke.sh)"
        fuzz_start=$SECONDS
        build_status=0
        wait "$fuzz_build_pid" || build_status=$?
        cat "$WORK/fuzz-build.log"
        if [[ $build_status -eq 0 ]]; then
            echo "(built beside steps 3 to 5; $((SECONDS - fuzz_start)) s of it waited for here)"
            bash "$ROOT/fuzz/smoke.sh" --no-build "$fuzz_seconds" || fuzz_status=$?
        else
            echo "fuzz smoke: the fuzz targets' build failed (exit $build_status)" >&2
            fuzz_status=$build_status
        fi
        fuzz_time="$((SECONDS - fuzz_start)) s after steps 3 to 5 (its build beside them)"
    else
        step 6 "fuzz smoke: skipped (VESSELMSR_FUZZ_SECONDS=0)"
    fi
fi

# Summary: counts of the Rust tests, the ignored tests by reason, the tests that skipped checks.
echo
echo "==== summary"
awk '/^test result:/ {
        for (i = 1; i <= NF; i++) {
            if ($(i) ~ /^passed;?$/) p += $(i - 1);
            if ($(i) ~ /^failed;?$/) f += $(i - 1);
            if ($(i) ~ /^ignored;?$/) g += $(i - 1);
        }
     }
     END { printf "rust tests: %d passed, %d failed, %d ignored\n", p, f, g }' "$LOG"
# "test NAME ... ignored, REASON" lines. The integration tests are one binary (tests/suite), whose
# test names carry their file as module (bvh_winding::slow::foo is in tests/suite/bvh_winding.rs):
# listed by name alone; an ignored test of another binary (the "Running unittests src/lib.rs (…)"
# or "Doc-tests vesselmsr" line before it) is prefixed with that binary.
ignored="$(awk '/^ *Running / { bin = ($2 == "unittests") ? $3 : $2; if (bin == "tests/suite/main.rs") bin = "" }
                /^ *Doc-tests / { bin = "doc-tests " $2 }
                / \.\.\. ignored/ { name = $0; sub(/^test /, "", name); sub(/ \.\.\. ignored.*/, "", name);
                                    reason = $0; sub(/.* \.\.\. ignored,? ?/, "", reason);
                                    if (reason == "") reason = "no reason given";
                                    print "  " (bin == "" ? "" : bin " ") name ": " reason }' "$LOG")"
if [[ -n "$ignored" ]]; then
    n_ignored=$(grep -c . <<<"$ignored")
    n_slow=$(grep -c ': slow:' <<<"$ignored" || true)
    if $slow; then
        echo "ignored and not run ($n_ignored):"
    else
        echo "ignored ($n_ignored; $n_slow slow, run by bash tests/run_slow.sh):"
    fi
    echo "$ignored"
fi
if [[ -s "$VESSELMSR_SKIPPED" ]]; then
    echo "skipped checks ($(sort -u "$VESSELMSR_SKIPPED" | grep -c .) tests skipped all or part of their checks):"
    sort -u "$VESSELMSR_SKIPPED" | sed 's/^/  /'
else
    echo "skipped checks: none"
fi
if $slow; then
    echo "time: cargo test ${rust_seconds} s"
else
    echo "time: cargo test ${rust_seconds} s, pytest reference ${py_seconds} s, wheel build and install ${wheel_seconds} s, pytest python ${pkg_seconds} s, fuzz smoke ${fuzz_time}"
fi

echo
if [[ $rust_status -ne 0 || $py_status -ne 0 || $wheel_status -ne 0 || $pkg_status -ne 0 ||
    $fuzz_status -ne 0 ]]; then
    echo "run_all: FAILED (cargo test exit $rust_status, pytest reference exit $py_status," \
        "wheel build exit $wheel_status, pytest python exit $pkg_status, fuzz smoke exit $fuzz_status)"
    exit 1
fi
if $slow; then
    echo "run_slow: all slow tests passed"
else
    echo "run_all: all steps passed"
fi
