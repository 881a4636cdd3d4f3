#!/usr/bin/env bash
# The slow real-mesh studies, apart from the quick suite (bash tests/run_all.sh): the Rust tests
# marked #[ignore = "slow: run by tests/run_slow.sh"] (in a module `slow` of their test file),
# run with the oracle venv, followed by the same summary. Extra arguments go to `cargo test`:
#
#   bash tests/run_slow.sh                      # every slow test
#   bash tests/run_slow.sh --test msr_cortex    # the slow tests of one file
exec bash "$(dirname "${BASH_SOURCE[0]}")/run_all.sh" --slow "$@"
