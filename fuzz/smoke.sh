#!/usr/bin/env bash
# Smoke run of every fuzz target (issue 22): builds the targets, then runs each for SECONDS
# (default 60) on a scratch copy of its seed corpus fuzz/seeds/<target>/, one after the other,
# under nice, with a 2 GiB RSS limit and a 10 s per-input timeout. Prints one line per target
# (executions, exec/s, corpus size, result) and the total wall time; exits 1 if any target
# crashed, timed out or ran out of memory (the input is kept in fuzz/artifacts/<target>/).
#
#   bash fuzz/smoke.sh          # 60 s per target
#   bash fuzz/smoke.sh 600      # the 10-minute runs of the acceptance
#
# cargo fuzz needs nightly flags (-Zsanitizer=address); RUSTC_BOOTSTRAP=1 lets the stable
# toolchain accept them. Needs cargo-fuzz (`cargo install cargo-fuzz`).
set -uo pipefail

seconds="${1:-60}"
cd "$(dirname "${BASH_SOURCE[0]}")"
FUZZ="$(pwd)"
start=$SECONDS

if ! command -v cargo-fuzz >/dev/null; then
    echo "smoke: cargo-fuzz is not installed (cargo install cargo-fuzz)" >&2
    exit 2
fi
echo "building the fuzz targets"
RUSTC_BOOTSTRAP=1 nice -n 19 cargo fuzz build -O || exit 2
BIN="$FUZZ/target/$(rustc -vV | sed -n 's/^host: //p')/release"

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
failed=0
for t in $(sed -n 's/^name = "\(.*\)"$/\1/p' Cargo.toml | grep -v '^vesselmsr-fuzz$'); do
    mkdir -p "$WORK/$t" "artifacts/$t"
    cp "seeds/$t"/* "$WORK/$t/"
    log="$WORK/$t.log"
    nice -n 19 "$BIN/$t" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
        -artifact_prefix="artifacts/$t/" -print_final_stats=1 "$WORK/$t" >"$log" 2>&1
    status=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    speed=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
    corpus=$(find "$WORK/$t" -type f | wc -l)
    if [[ $status -eq 0 ]]; then
        result=ok
    else
        result="FAILED (exit $status): $(grep -m1 -E '^(==[0-9]+== ?ERROR|SUMMARY|ERROR)' "$log")"
        failed=1
        tail -40 "$log" >&2
    fi
    printf '%-8s %10s execs %7s exec/s %5s inputs  %s\n' "$t" "${execs:-?}" "${speed:-?}" "$corpus" "$result"
done
echo "smoke: $((SECONDS - start)) s wall time (${seconds} s per target, build included)"
exit $failed
