#!/usr/bin/env bash
# Soak test. Called by `scripts/run soak [minutes] [--sim] [options]` after setup +
# build, with the workspace sourced. Runs the simulated drive in real time at 600 rpm
# (10 revolutions/s) through the full pipeline in one nodelet manager on its own ROS master:
#   default  a pcap of the simulated drive (60 s, written once by urban_detection_simulate into
#            results/) replayed in a loop by PacketSource at the recorded pace (pcap.launch):
#            the machine's time goes to the pipeline, not to ray casting;
#   --sim    SimulatedSensor casting rays live (demo.launch); on a slow machine the simulator
#            itself lags behind real time and its lag shows up as latency.
# scripts/soak_monitor.py measures latency, skipped revolutions and the manager's resident
# memory after a warm-up, and writes results/soak_<minutes>min.json.
#   scripts/run soak            30 minutes (the figure reported in the README)
#   scripts/run soak 2          the CI version (2 minutes, 30 s warm-up)
# Further options: --warmup S, and the failure bounds of soak_monitor.py: --max-rss-growth-mb MB
# (default 20, RSS at the end minus RSS after the warm-up), --max-skipped-fraction F (0.01),
# --expected-rate-hz HZ (10) with --rate-tolerance F (0.05: /objects must come at 9.5..10.5 Hz),
# --max-clock-disagreement F (0.01). A revolution received twice also fails. Exit status 1 when
# a bound is exceeded or a process died. Run it niced on a shared machine:
# `nice -n 10 scripts/run soak`.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
OUT="$REPO/results"
MINUTES="${1:-30}"
[ $# -gt 0 ] && shift
WARMUP=60
if awk "BEGIN { exit !($MINUTES < 10) }"; then WARMUP=30; fi
SOURCE=pcap
if [ "${1:-}" = "--sim" ]; then SOURCE=sim; shift; fi
mkdir -p "$OUT"
JSON="$OUT/soak_${MINUTES}min.json"
LOG="$OUT/soak_${MINUTES}min_roslaunch.log"

PORT="$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
export ROS_MASTER_URI="http://127.0.0.1:$PORT"
export ROS_HOME="${ROS_HOME:-$OUT/ros_home}"
LAUNCH_PID=""
cleanup() {
  if [ -n "$LAUNCH_PID" ] && kill -0 "$LAUNCH_PID" 2>/dev/null; then
    kill -INT "$LAUNCH_PID" 2>/dev/null || true
    for _ in $(seq 1 20); do kill -0 "$LAUNCH_PID" 2>/dev/null || break; sleep 0.5; done
    kill -KILL "$LAUNCH_PID" 2>/dev/null || true
  fi
}
trap cleanup EXIT

echo "soak: ${MINUTES} min after ${WARMUP} s warm-up, source $SOURCE, master $ROS_MASTER_URI, log $LOG" >&2
if [ "$SOURCE" = pcap ]; then
  PCAP="$OUT/soak_drive.pcap"
  SIM="$(ud_workspace "$REPO")/devel/lib/urban_detection/urban_detection_simulate"
  # Regenerated when the simulator or the drive description is newer than the cached file.
  if [ ! -s "$PCAP" ] || [ "$SIM" -nt "$PCAP" ] || [ "$REPO/config/demo_drive.yaml" -nt "$PCAP" ]; then
    echo "soak: writing $PCAP (600 simulated revolutions)" >&2
    "$SIM" --config "$REPO/config/demo_drive.yaml" --revolutions 600 --pcap "$PCAP.tmp" >/dev/null
    mv "$PCAP.tmp" "$PCAP"
  fi
  LAUNCH=(pcap.launch "pcap:=$PCAP" loop:=true rate:=1.0)
else
  LAUNCH=(demo.launch)
fi
roslaunch -p "$PORT" urban_detection "${LAUNCH[@]}" rviz:=false >"$LOG" 2>&1 &
LAUNCH_PID=$!
# The monitor registers once the master answers (a rospy node started before its master
# registers its subscriptions twice, through two racing paths).
for _ in $(seq 1 60); do
  /usr/bin/python3 -c 'import sys, rosgraph; sys.exit(0 if rosgraph.is_master_online() else 1)' \
      2>/dev/null && break
  sleep 0.5
done
set +e
/usr/bin/python3 "$REPO/scripts/soak_monitor.py" --minutes "$MINUTES" --warmup "$WARMUP" \
    --source "$SOURCE" --out "$JSON" "$@"
STATUS=$?
set -e
if ! kill -0 "$LAUNCH_PID" 2>/dev/null; then
  echo "soak: roslaunch exited early; last lines of $LOG:" >&2
  tail -n 20 "$LOG" >&2
  STATUS=1
fi
if grep -qE "process has died|Segmentation fault|terminate called" "$LOG"; then
  echo "soak: a process died; see $LOG" >&2
  STATUS=1
fi
echo "soak: summary in $JSON (exit $STATUS)" >&2
exit "$STATUS"
