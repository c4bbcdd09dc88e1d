#!/usr/bin/env bash
# Checks formatting, lints and doc links, then runs every Ridgeline test. On a fresh Debian machine (as root) it first
# installs the Mesa packages the headless GL tests need (scripts/mesa.sh).
# `.ci/run` calls exactly this, as the README says. The last line totals the
# tests of every test binary.
set -euo pipefail
cd "$(dirname "$0")/.."
sh scripts/mesa.sh

# In CI the GL backends are installed above, so their tests must run, not skip.
if [ "${CI:-}" = true ]; then
    export RIDGELINE_REQUIRE_OSMESA=1 RIDGELINE_REQUIRE_WINDOW=1
fi

# Style first: formatting and lints are part of the suite.
cargo fmt --check
cargo clippy --locked --all-targets -- -D warnings
RUSTDOCFLAGS='-D warnings' cargo doc --locked --no-deps --quiet

log=$(mktemp)
trap 'rm -f "$log"' EXIT
cargo test --locked 2>&1 | tee "$log"
total() { grep -o "[0-9]* $1;" "$log" | awk '{ n += $1 } END { print n + 0 }'; }
echo "tests: $(total passed) passed, $(total failed) failed"
