#!/bin/sh
# Runs the main job, `ridgeline fly`, with any options given (see
# `cargo run --release -- fly --help`). On a fresh Debian machine (as root) it
# first installs the Mesa packages the GL backends need (scripts/mesa.sh).
set -eu
cd "$(dirname "$0")/.."
sh scripts/mesa.sh
exec cargo run --release --locked -- fly "$@"
