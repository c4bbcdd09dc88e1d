#!/bin/sh
# Runs every Ridgeline test. On a fresh Debian machine (as root) it first
# installs the Mesa packages the headless GL tests need (scripts/mesa.sh).
# `.ci/run` calls exactly this, as the README says.
set -eu
cd "$(dirname "$0")/.."
sh scripts/mesa.sh

# In CI the GL backends are installed above, so their tests must run, not skip.
if [ "${CI:-}" = true ]; then
    export RIDGELINE_REQUIRE_OSMESA=1 RIDGELINE_REQUIRE_WINDOW=1
fi

exec cargo test --locked
