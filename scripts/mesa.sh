#!/bin/sh
# Installs what Ridgeline's GL backends need on Debian when it is missing:
# EGL and GLES (headless rendering), OSMesa (regression tests), Xvfb and the
# X libraries winit opens a window with. Needs root and apt-get; elsewhere it
# only says what is missing. Used by scripts/fly.sh and scripts/test.sh.
set -eu

need_pkgs=""
have() { dpkg -s "$1" >/dev/null 2>&1; }
for pkg in libegl1 libegl-mesa0 libgles2 libgl1-mesa-dri libosmesa6 xvfb \
    libxkbcommon-x11-0 libxcursor1 libxi6 libxrandr2; do
    have "$pkg" || need_pkgs="$need_pkgs $pkg"
done
if [ -n "$need_pkgs" ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "scripts/mesa.sh: installing$need_pkgs" >&2
        apt-get update -qq >/dev/null
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $need_pkgs >/dev/null
    else
        echo "scripts/mesa.sh: missing$need_pkgs; install them for the GL backends" >&2
    fi
fi
