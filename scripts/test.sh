#!/bin/sh
# Runs every Ridgeline test. On a fresh Debian machine (as root) it first
# installs the Mesa packages the headless GL tests need; elsewhere it uses what
# is there. `.ci/run` calls exactly this, as the README says.
set -eu
cd "$(dirname "$0")/.."

need_pkgs=""
have() { dpkg -s "$1" >/dev/null 2>&1; }
for pkg in libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri libosmesa6 xvfb; do
    have "$pkg" || need_pkgs="$need_pkgs $pkg"
done
if [ -n "$need_pkgs" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "scripts/test.sh: installing$need_pkgs" >&2
        apt-get update -qq >/dev/null
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $need_pkgs >/dev/null
    else
        echo "scripts/test.sh: missing$need_pkgs; GL tests that need them will say so" >&2
    fi
fi

exec cargo test --locked
