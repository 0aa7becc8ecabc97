#!/usr/bin/env bash
# rviz screenshot of the simulated drive through the detection chain. Called by
# `scripts/run screenshot` after setup + build, with the workspace sourced.
#   starts Xvfb (software GL) and its own ROS master on free ports, runs
#   `roslaunch urban_detection demo.launch rviz:=true`, waits, grabs the X root window with
#   ImageMagick's `import` into results/screenshot.png, then checks the image with
#   scripts/check_screenshot.py (not blank, point colours and object-marker colours present).
# Options: --wait SECONDS (default 25) before the grab; --kitti: a KITTI raw drive of the shared
# data (converted by urban_detection_kitti_to_bag, looped by bag.launch) instead of the
# simulated drive (also the fallback when demo.launch is absent); further args go to roslaunch.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
OUT="$REPO/results"
DATA="${UD_SHARED_DATA:-$REPO/../shared/data}"
WAIT_S=25
KITTI=0
while [ $# -gt 0 ]; do
  case "$1" in
    --wait) WAIT_S="$2"; shift 2 ;;
    --kitti) KITTI=1; shift ;;
    *) break ;;
  esac
done
mkdir -p "$OUT"
[ -f "$REPO/launch/demo.launch" ] || KITTI=1
LAUNCH=(demo.launch)
if [ "$KITTI" = 1 ]; then
  DRIVE="$DATA/kitti_raw/drive_0048"
  [ -d "$DRIVE" ] || { echo "screenshot: no demo.launch and no $DRIVE" >&2; exit 1; }
  BIN="$(ud_workspace "$REPO")/devel/lib/urban_detection"
  "$BIN/urban_detection_kitti_to_bag" "$DRIVE" "$OUT/screenshot_kitti.bag" >/dev/null
  LAUNCH=(bag.launch "bag:=$OUT/screenshot_kitti.bag" loop:=true delay:=1)
fi
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
roslaunch -p "$MASTER_PORT" urban_detection "${LAUNCH[@]}" rviz:=true "$@" >"$LOG" 2>&1 &
LAUNCH_PID=$!
echo "screenshot: ${LAUNCH[*]} rviz:=true on $DISPLAY (master :$MASTER_PORT), waiting ${WAIT_S} s"
sleep "$WAIT_S"
kill -0 "$LAUNCH_PID" 2>/dev/null || { tail -n 30 "$LOG"; echo "screenshot: roslaunch exited" >&2; exit 1; }
import -display "$DISPLAY" -window root "$PNG"
echo "screenshot: $PNG"
/usr/bin/python3 "$REPO/scripts/check_screenshot.py" "$PNG"
