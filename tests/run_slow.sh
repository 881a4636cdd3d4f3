#!/usr/bin/env bash
# The slow real-mesh studies, apart from the quick suite (bash tests/run_all.sh): the Rust tests
# marked #[ignore = "slow: run by tests/run_slow.sh"] (in a module `slow` of their test module,
# e.g. msr_cortex::slow:: in tests/suite/msr_cortex.rs), run with the oracle venv, followed by the
# same summary: `cargo test --release -- --ignored slow::`. Extra arguments go to `cargo test`; a
# filter among them (a test path, with "::") replaces slow:: (libtest runs the tests matching any
# one of its filters, so adding it would still run them all):
#
#   bash tests/run_slow.sh                          # every slow test
#   bash tests/run_slow.sh msr_cortex::slow::       # the slow tests of tests/suite/msr_cortex.rs
exec bash "$(dirname "${BASH_SOURCE[0]}")/run_all.sh" --slow "$@"
