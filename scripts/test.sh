#!/bin/sh
# Runs every Ridgeline test. On a fresh Debian machine (as root) it first
# installs the Mesa packages the headless GL tests need; elsewhere it uses what
# is there. `.ci/run` calls exactly this, as the README says.
set -eu
cd "$(dirname "$0")/.."

need_pkgs=""
have() { dpkg -s "$1" >/dev/null 2>&1; }
# EGL and GLES for headless rendering, OSMesa for the regression tests,
# Xvfb and the X libraries winit opens a window with.
for pkg in libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri libosmesa6 xvfb \
    libxkbcommon-x11-0 libxcursor1 libxi6 libxrandr2; do
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

# In CI the GL backends are installed above, so their tests must run, not skip.
if [ "${CI:-}" = true ]; then
    export RIDGELINE_REQUIRE_OSMESA=1 RIDGELINE_REQUIRE_WINDOW=1
fi

exec cargo test --locked
