#!/usr/bin/env bash
# rviz screenshot of the simulated drive through the detection chain (issue 7). Called by
# `scripts/run screenshot` after setup + build, with the workspace sourced.
#   starts Xvfb (software GL) and its own ROS master on free ports, runs
#   `roslaunch urban_detection demo.launch rviz:=true`, waits, grabs the X root window with
#   ImageMagick's `import` into results/screenshot.png, then checks the image with
#   scripts/check_screenshot.py (not blank, point colours and object-marker colours present).
# Options: --wait SECONDS (default 25) before the grab; further args go to demo.launch.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$REPO/results"
WAIT_S=25
if [ "${1:-}" = "--wait" ]; then WAIT_S="$2"; shift 2; fi
mkdir -p "$OUT"
PNG="$OUT/screenshot.png"
LOG="$OUT/screenshot_roslaunch.log"

free_port() {
  /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
free_display() {
  local d
  for d in $(seq 90 140); do
    [ -e "/tmp/.X$d-lock" ] || [ -e "/tmp/.X11-unix/X$d" ] || { echo "$d"; return; }
  done
  echo "screenshot: no free X display number in 90..140" >&2; exit 1
}

DISPLAY_NUM="$(free_display)"
XVFB_PID="" LAUNCH_PID=""
cleanup() {
  [ -n "$LAUNCH_PID" ] && kill -INT "$LAUNCH_PID" 2>/dev/null && sleep 3
  [ -n "$LAUNCH_PID" ] && kill -KILL "$LAUNCH_PID" 2>/dev/null
  [ -n "$XVFB_PID" ] && kill "$XVFB_PID" 2>/dev/null
  true
}
trap cleanup EXIT

Xvfb ":$DISPLAY_NUM" -screen 0 1400x900x24 -nolisten tcp >/dev/null 2>&1 &
XVFB_PID=$!
sleep 2
kill -0 "$XVFB_PID" 2>/dev/null || { echo "screenshot: Xvfb :$DISPLAY_NUM failed to start" >&2; exit 1; }

export DISPLAY=":$DISPLAY_NUM" LIBGL_ALWAYS_SOFTWARE=1
MASTER_PORT="$(free_port)"
export ROS_MASTER_URI="http://127.0.0.1:$MASTER_PORT"
roslaunch -p "$MASTER_PORT" urban_detection demo.launch rviz:=true "$@" >"$LOG" 2>&1 &
LAUNCH_PID=$!
echo "screenshot: demo.launch rviz:=true on $DISPLAY (master :$MASTER_PORT), waiting ${WAIT_S} s"
sleep "$WAIT_S"
kill -0 "$LAUNCH_PID" 2>/dev/null || { tail -n 30 "$LOG"; echo "screenshot: roslaunch exited" >&2; exit 1; }
import -display "$DISPLAY" -window root "$PNG"
echo "screenshot: $PNG"
/usr/bin/python3 "$REPO/scripts/check_screenshot.py" "$PNG"
