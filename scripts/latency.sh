#!/usr/bin/env bash
# Latency of the live chain. Called by `scripts/run latency [seconds] [options]` after
# setup + build, with the workspace sourced. Replays the simulated drive's pcap as UDP datagrams
# at the sensor's pace (urban_detection_udp_replay) into live.launch on its own ROS master and
# UDP port, and measures with urban_detection_latency_probe, per revolution, the time from the
# revolution's last packet (its header.stamp: PacketSource stamps each packet on receipt) to the
# arrival of /objects and /objects/markers in another process. Writes
# results/latency[_<detector>].json: the probe's figures, the replay's pacing and the machine.
#   scripts/run latency                    60 s, detector:=hierarchical
#   scripts/run latency 60 --detector both the hierarchical chain beside the kd-tree baseline
#   scripts/run latency 60 --camera        the same with the camera stage in the
#                                          manager: ENet (config/spark_enet_cityscapes.yaml) on a
#                                          KITTI image at 10 Hz (urban_detection_camera_replay);
#                                          also measures objects/classified
#   scripts/run latency 60 --early         early objects on (early_objects:=true): also
#                                          measures objects/early, each object from its own
#                                          last point (results/latency_early.json)
# Further options: --warmup S (default 10), --launch-arg NAME:=VALUE (repeatable).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
BIN="$(ud_workspace "$REPO")/devel/lib/urban_detection"
OUT="$REPO/results"
SECONDS_TO_MEASURE="${1:-60}"
[ $# -gt 0 ] && shift
WARMUP=10
DETECTOR=hierarchical
EXTRA=()
CAMERA=false
EARLY=false
while [ $# -gt 0 ]; do
  case "$1" in
    --warmup) WARMUP="$2"; shift 2 ;;
    --detector) DETECTOR="$2"; shift 2 ;;
    --launch-arg) EXTRA+=("$2"); shift 2 ;;
    --camera) CAMERA=true; shift ;;
    --early) EARLY=true; EXTRA+=(early_objects:=true); shift ;;
    *) echo "latency: unknown option $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$OUT"
SUFFIX=""
[ "$DETECTOR" != hierarchical ] && SUFFIX="_$DETECTOR"
[ "$CAMERA" = true ] && SUFFIX="${SUFFIX}_camera"
[ "$EARLY" = true ] && SUFFIX="${SUFFIX}_early"
JSON="$OUT/latency$SUFFIX.json"
LOG="$OUT/latency${SUFFIX}_roslaunch.log"
PCAP="$OUT/soak_drive.pcap"  # shared with scripts/soak.sh
if [ ! -s "$PCAP" ] || [ "$BIN/urban_detection_simulate" -nt "$PCAP" ] ||
   [ "$REPO/config/demo_drive.yaml" -nt "$PCAP" ]; then
  echo "latency: writing $PCAP (600 simulated revolutions)" >&2
  "$BIN/urban_detection_simulate" --config "$REPO/config/demo_drive.yaml" --revolutions 600 \
      --pcap "$PCAP.tmp" >/dev/null
  mv "$PCAP.tmp" "$PCAP"
fi

free_port() {
  /usr/bin/python3 -c "import socket; s = socket.socket(socket.AF_INET, socket.$1); s.bind(('127.0.0.1', 0)); print(s.getsockname()[1])"
}
MASTER_PORT="$(free_port SOCK_STREAM)"
UDP_PORT="$(free_port SOCK_DGRAM)"
export ROS_MASTER_URI="http://127.0.0.1:$MASTER_PORT"
export ROS_HOME="${ROS_HOME:-$OUT/ros_home}"
LAUNCH_PID=""
REPLAY_PID=""
CAMERA_PIDS=()
cleanup() {
  [ -n "$REPLAY_PID" ] && kill "$REPLAY_PID" 2>/dev/null || true
  for p in "${CAMERA_PIDS[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  if [ -n "$LAUNCH_PID" ] && kill -0 "$LAUNCH_PID" 2>/dev/null; then
    kill -INT "$LAUNCH_PID" 2>/dev/null || true
    for _ in $(seq 1 20); do kill -0 "$LAUNCH_PID" 2>/dev/null || break; sleep 0.5; done
    kill -KILL "$LAUNCH_PID" 2>/dev/null || true
  fi
}
trap cleanup EXIT

echo "latency: ${SECONDS_TO_MEASURE} s after ${WARMUP} s warm-up, detector $DETECTOR, master $ROS_MASTER_URI, UDP $UDP_PORT, log $LOG" >&2
roslaunch -p "$MASTER_PORT" urban_detection live.launch "port:=$UDP_PORT" device_ip:=127.0.0.1 \
    "detector:=$DETECTOR" rviz:=false "${EXTRA[@]}" >"$LOG" 2>&1 &
LAUNCH_PID=$!
for _ in $(seq 1 60); do
  /usr/bin/python3 -c 'import sys, rosgraph; sys.exit(0 if rosgraph.is_master_online() else 1)' \
      2>/dev/null && break
  sleep 0.5
done
if [ "$CAMERA" = true ]; then
  DATA="${UD_SHARED_DATA:-$REPO/../shared/data}"
  [ -f "$DATA/models/enet-cityscapes/enet-model.net" ] && [ -d "$DATA/kitti_object/image_2" ] || {
    echo "latency: --camera needs $DATA/models/enet-cityscapes and $DATA/kitti_object" >&2; exit 1; }
  "$BIN/urban_detection_camera_replay" --kitti "$DATA/kitti_object" --rate 10 \
      >"$OUT/latency${SUFFIX}_camera_replay.log" 2>&1 &
  CAMERA_PIDS+=($!)
  roslaunch urban_detection image_label_transfer.launch markers:=false \
      "config:=$REPO/config/spark_enet_cityscapes.yaml" \
      "model_dir:=$DATA/models/enet-cityscapes" >"$OUT/latency${SUFFIX}_camera.log" 2>&1 &
  CAMERA_PIDS+=($!)
fi
TOPICS=(--objects objects --markers objects/markers)
[ "$CAMERA" = true ] && TOPICS+=(--objects objects/classified)
if [ "$DETECTOR" = both ]; then
  TOPICS+=(--objects kdtree/objects --markers kdtree/objects/markers)
elif [ "$DETECTOR" = kdtree ]; then
  TOPICS=(--objects objects --markers objects/markers)
fi
[ "$EARLY" = true ] && TOPICS+=(--stamped-objects objects/early)
# The probe subscribes first (the chain is lazy), then the sensor starts sending.
PROBE_JSON="$JSON.probe"
"$BIN/urban_detection_latency_probe" "${TOPICS[@]}" --warmup "$WARMUP" \
    --duration "$SECONDS_TO_MEASURE" --out "$PROBE_JSON" &
PROBE_PID=$!
TOTAL=$(awk "BEGIN { print $SECONDS_TO_MEASURE + $WARMUP + 20 }")
"$BIN/urban_detection_udp_replay" --pcap "$PCAP" --port "$UDP_PORT" --loop --start-delay 5 \
    --duration "$TOTAL" 2>"$JSON.replay" &
REPLAY_PID=$!
set +e
wait "$PROBE_PID"
STATUS=$?
set -e
kill "$REPLAY_PID" 2>/dev/null || true
wait "$REPLAY_PID" 2>/dev/null || true
REPLAY_PID=""
if ! kill -0 "$LAUNCH_PID" 2>/dev/null || grep -qE "process has died|Segmentation fault|terminate called" "$LOG"; then
  echo "latency: the pipeline died; see $LOG" >&2
  STATUS=1
fi
/usr/bin/python3 - "$PROBE_JSON" "$JSON.replay" "$JSON" "$DETECTOR" <<'PY'
import json, os, platform, sys
probe_path, replay_path, out_path, detector = sys.argv[1:5]
try:
    probe = json.load(open(probe_path))
except (OSError, ValueError):
    probe = {'error': 'no probe output'}
replay = {}
for line in open(replay_path, errors='replace'):
    line = line.strip()
    if line.startswith('{'):
        try:
            replay = json.loads(line)
        except ValueError:
            pass
cpu = ''
try:
    for line in open('/proc/cpuinfo'):
        if line.startswith('model name'):
            cpu = line.split(':', 1)[1].strip()
            break
except OSError:
    pass
result = {'what': 'last packet of a revolution (its header.stamp) -> message received by a '
                  'subscriber in another process, live.launch fed over UDP at the sensor pace',
          'detector': detector, 'machine': {'cpu': cpu, 'cores': os.cpu_count(),
                                            'system': platform.platform()},
          'input': 'simulated drive (config/demo_drive.yaml) pcap, UDP replay on 127.0.0.1',
          'replay': replay, **probe}
json.dump(result, open(out_path, 'w'), indent=1)
for topic, t in sorted(probe.get('topics', {}).items()):
    if 'p50_ms' in t:
        print('latency %-28s %6.1f Hz  p50 %6.2f  p95 %6.2f  p99 %6.2f  max %6.2f ms  (%d)' % (
            topic, t['rate_hz'], t['p50_ms'], t['p95_ms'], t['p99_ms'], t['max_ms'], t['messages']))
    else:
        print('latency %-28s no messages' % topic)
PY
rm -f "$PROBE_JSON" "$JSON.replay"
echo "latency: $JSON (exit $STATUS)" >&2
exit "$STATUS"
