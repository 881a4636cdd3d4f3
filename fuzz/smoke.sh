#!/usr/bin/env bash
# Smoke run of the fuzz targets (issue 22); step 6 of tests/run_all.sh runs it at 60 s.
#
#   bash fuzz/smoke.sh [--asan] [--build-only | --no-build] [SECONDS] [TARGET...]
#
# Builds the targets, then runs them all at once (or the TARGETs named), each for SECONDS of
# wall time (default 60) on a scratch copy of its seeds fuzz/seeds/<target>/, under nice, with a
# 2 GiB RSS limit and a 10 s per-input timeout. Prints one line per target (executions, exec/s,
# inputs in the corpus at the end, peak RSS, result); exits 1 if any target crashed (a panic is
# an abort), timed out or ran out of memory, keeping the input in fuzz/artifacts/<target>/ and
# printing the end of its log; exits 2 if the build failed.
#
# The default build is plain cargo on the stable toolchain, no cargo-fuzz: `cargo build
# --profile smoke` (release with debug assertions and overflow checks, fuzz/Cargo.toml) with the
# coverage flags cargo fuzz passes, without AddressSanitizer (the readers are safe Rust; what the
# smoke catches is panics, aborts, hangs and memory). libFuzzer's -malloc_limit_mb needs a
# sanitizer's malloc hooks, so the plain build limits the address space instead (ulimit -v
# 2 GiB): an allocation beyond it fails and aborts, as -malloc_limit_mb=2048 would report it.
#
# --asan builds with cargo-fuzz instead (`cargo install cargo-fuzz`): `cargo fuzz build -O -a`,
# AddressSanitizer, release with debug assertions, ~8 min cold on 2 cores; for the long runs:
#
#   bash fuzz/smoke.sh                  # every target, 60 s, all at once
#   bash fuzz/smoke.sh --asan 600 stl   # one target for 10 minutes under AddressSanitizer
#
# --build-only builds and exits; --no-build runs what the last build left (tests/run_all.sh
# builds while its Python steps run, which leave a core idle, then runs the targets).
set -uo pipefail

usage="usage: bash fuzz/smoke.sh [--asan] [--build-only | --no-build] [SECONDS] [TARGET...]"
asan=false
build=true
run=true
while [[ "${1:-}" == --* ]]; do
    case "$1" in
    --asan) asan=true ;;
    --build-only) run=false ;;
    --no-build) build=false ;;
    *)
        echo "$usage" >&2
        exit 2
        ;;
    esac
    shift
done
if ! $build && ! $run; then
    echo "smoke: --build-only and --no-build together do nothing" >&2
    exit 2
fi
seconds="${1:-60}"
if ! [[ "$seconds" =~ ^[1-9][0-9]*$ ]]; then
    echo "$usage" >&2
    exit 2
fi
shift $(($# > 0 ? 1 : 0))
cd "$(dirname "${BASH_SOURCE[0]}")"
FUZZ="$(pwd)"
all=($(sed -n 's/^name = "\(.*\)"$/\1/p' Cargo.toml | grep -v '^vesselmsr-fuzz$'))
if (($#)); then targets=("$@"); else targets=("${all[@]}"); fi
for t in "${targets[@]}"; do
    if [[ ! " ${all[*]} " == *" $t "* ]]; then
        echo "smoke: no fuzz target $t (targets: ${all[*]})" >&2
        exit 2
    fi
done
host="$(rustc -vV | sed -n 's/^host: //p')"
start=$SECONDS

# cargo builds into $CARGO_TARGET_DIR when it is set (a relative one from fuzz/, where it runs).
target_dir="${CARGO_TARGET_DIR:-$FUZZ/target}"
if $asan; then
    BIN="$target_dir/$host/release"
else
    BIN="$target_dir/$host/smoke"
fi
if $build && $asan; then
    if ! command -v cargo-fuzz >/dev/null; then
        echo "smoke: cargo-fuzz is not installed (cargo install cargo-fuzz)" >&2
        exit 2
    fi
    echo "building the fuzz targets: cargo fuzz build -O -a (AddressSanitizer)"
    # cargo fuzz passes -Zsanitizer=address; RUSTC_BOOTSTRAP=1 lets the stable toolchain accept it.
    RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz build -O -a || exit 2
elif $build; then
    echo "building the fuzz targets: cargo build --profile smoke, coverage flags, no sanitizer"
    # cargo fuzz's flags but -Csanitizer, -Clink-dead-code and -Ccodegen-units=1 (faster to
    # build). --target keeps them off build scripts and proc macros.
    flags=(--cfg fuzzing -Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4
        -Cllvm-args=-sanitizer-coverage-inline-8bit-counters
        -Cllvm-args=-sanitizer-coverage-pc-table -Cllvm-args=-sanitizer-coverage-trace-compares
        -Cllvm-args=-sanitizer-coverage-stack-depth
        -Cllvm-args=-simplifycfg-branch-fold-threshold=0)
    RUSTFLAGS="${flags[*]}" nice -n 19 cargo build --profile smoke --target "$host" || exit 2
fi
built=$SECONDS
if ! $run; then
    echo "built in $((built - start)) s"
    exit 0
fi
if $build; then
    echo "built in $((built - start)) s; running ${targets[*]} for $seconds s each, all at once"
else
    for t in "${targets[@]}"; do
        if [[ ! -x "$BIN/$t" ]]; then
            echo "smoke: $BIN/$t is not built (run without --no-build)" >&2
            exit 2
        fi
    done
    echo "running ${targets[*]} for $seconds s each, all at once (built beforehand)"
fi

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
declare -A pid
for t in "${targets[@]}"; do
    mkdir -p "$WORK/$t" "artifacts/$t"
    cp "seeds/$t"/* "$WORK/$t/"
    (
        $asan || ulimit -v $((2048 * 1024))
        export RUST_BACKTRACE="${RUST_BACKTRACE:-1}" # a panic's backtrace in the log
        # The outer timeout only guards against a fuzzer that does not stop by itself.
        exec nice -n 19 timeout -k 10 $((seconds + 120)) "$BIN/$t" -max_total_time="$seconds" \
            -rss_limit_mb=2048 -timeout=10 -artifact_prefix="$FUZZ/artifacts/$t/" \
            -print_final_stats=1 "$WORK/$t"
    ) >"$WORK/$t.log" 2>&1 &
    pid[$t]=$!
done

failed=0
printf '%-8s %10s %7s %7s %5s  %s\n' target execs exec/s inputs rss result
for t in "${targets[@]}"; do
    wait "${pid[$t]}"
    status=$?
    log="$WORK/$t.log"
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
    rss=$(sed -n 's/^stat::peak_rss_mb: *//p' "$log")
    corpus=$(find "$WORK/$t" -type f | wc -l)
    if [[ $status -eq 0 ]]; then
        result=ok
    else
        failed=1
        if [[ $status -eq 124 || $status -eq 137 ]]; then
            why="did not stop within $((seconds + 120)) s, killed"
        else
            why="$(grep -m1 -E '^==[0-9]+== ?ERROR' "$log")"
        fi
        result="FAILED (exit $status): ${why:-see the log}"
        {
            echo "---- end of the log of $t"
            tail -40 "$log"
            echo "----"
        } >&2
    fi
    printf '%-8s %10s %7s %7s %5s  %s\n' "$t" "${execs:-?}" "${speed:-?}" "$corpus" \
        "${rss:-?}M" "$result"
    grep -A1 -E '(panicked at|^memory allocation of|Test unit written to)' "$log" | grep -v '^--$' | head -4 |
        sed 's/^/         /'
done
echo "smoke: $((SECONDS - start)) s wall time (build $((built - start)) s, run $((SECONDS - built)) s)"
exit $failed
