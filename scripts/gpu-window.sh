#!/usr/bin/env bash
# gpu-window.sh: runs a command (prt-play's window, the window tests) on a machine with an NVIDIA GPU
# and no display: starts a virtual X server (Xvfb) whose GLX clients use the NVIDIA driver's GLX
# library (__GLX_VENDOR_LIBRARY_NAME=nvidia), so that prt-play's GL context runs on the CUDA device
# and CUDA-OpenGL interop works; the command runs with DISPLAY set, then the server stops.
#
# Usage: scripts/gpu-window.sh [--root DIR] [--screen WxH] -- COMMAND [ARGS...]
#   --root DIR     Debian packages unpacked into DIR (dpkg -x PKG DIR for xvfb, xkb-data,
#                  x11-xkb-utils, libgl1-mesa-dri and their libraries, libglfw3): Xvfb, xkbcomp and the
#                  libraries are taken from there, for a machine where they are not installed
#                  [none: the system's Xvfb]
#   --screen WxH   the virtual screen, 24-bit [1920x1080; a window larger than it is cut]
# Environment: DISPLAY_NUMBER picks the display [99].
set -euo pipefail

root="" screen=1920x1080
while [ $# -gt 0 ]; do
    case $1 in
        --root) root=$(cd "$2" && pwd); shift 2 ;;
        --screen) screen=$2; shift 2 ;;
        --) shift; break ;;
        -h | --help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "gpu-window.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    esac
done
[ $# -gt 0 ] || { echo "gpu-window.sh: no command given (see --help)" >&2; exit 2; }

xvfb=Xvfb xargs=()
if [ -n "$root" ]; then
    lib=$root/usr/lib/x86_64-linux-gnu
    export LD_LIBRARY_PATH=$lib:$root/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export LIBGL_DRIVERS_PATH=$lib/dri   # the server's own GLX (Mesa's software renderer)
    xvfb=$root/usr/bin/Xvfb
    xargs=(-xkbdir "$root/usr/share/X11/xkb")
    # Xvfb runs xkbcomp from its built-in folder (/usr/bin) to compile the keymap.
    if ! command -v xkbcomp >/dev/null 2>&1; then
        ln -sf "$root/usr/bin/xkbcomp" /usr/bin/xkbcomp 2>/dev/null ||
            { echo "gpu-window.sh: xkbcomp is not installed and /usr/bin is not writable" >&2; exit 1; }
    fi
fi
command -v "$xvfb" >/dev/null 2>&1 || { echo "gpu-window.sh: Xvfb not found (Debian: apt-get install xvfb)" >&2; exit 1; }

display=:${DISPLAY_NUMBER:-99}
log=$(mktemp /tmp/gpu-window-xvfb.XXXXXX)
"$xvfb" "$display" -screen 0 "${screen}x24" -nolisten tcp "${xargs[@]}" >"$log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null; wait $server 2>/dev/null; rm -f "$log"' EXIT
for _ in $(seq 50); do  # up to 5 s for the server's socket
    [ -S "/tmp/.X11-unix/X${display#:}" ] && break
    kill -0 $server 2>/dev/null || { echo "gpu-window.sh: Xvfb stopped:" >&2; cat "$log" >&2; exit 1; }
    sleep 0.1
done
export DISPLAY=$display __GLX_VENDOR_LIBRARY_NAME=nvidia
"$@"
