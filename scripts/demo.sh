#!/usr/bin/env bash
# `scripts/run demo`: the simulated demo drive (config/demo_drive.yaml, results/sim) scored by
# urban_detection_eval exactly as `scripts/run eval` scores it (shipped configs and classifier,
# --min-points 30, the first 40 revolutions), so its figures are the README's. Writes
# results/demo/eval.{txt,json}, a top view per revolution (results/demo/*.png: ground truth left,
# detections right, in the class colours of rviz; yellow boxes missed objects, red boxes false
# detections) and copies the busiest revolution to results/demo.png. Prints the per-class table
# and where the picture is. Extra arguments go to urban_detection_eval.
# Per-stage timings of the same chain: scripts/run bench (its `sim` row is this drive).
set -euo pipefail
# shellcheck source=tool_env.sh
source "$(dirname "${BASH_SOURCE[0]}")/tool_env.sh"  # REPO BIN DATA OUT PIN CONFIGS

for tool in urban_detection_eval urban_detection_simulate; do
  [ -x "$BIN/$tool" ] || { echo "demo: $BIN/$tool is not built" >&2; exit 1; }
done
DEMO="$OUT/demo"
mkdir -p "$DEMO"
rm -f "$DEMO"/*.png
bash "$REPO/scripts/sim_drive.sh" "$OUT/sim"
echo "== demo: urban_detection_eval on the simulated drive (as scripts/run eval)"
"${PIN[@]}" "$BIN/urban_detection_eval" --sim "$OUT/sim/drive.gt" --pcap "$OUT/sim/drive.pcap" \
    --max-frames 40 "${CONFIGS[@]}" --png "$DEMO" --json "$DEMO/eval.json" "$@" \
    | tee "$DEMO/eval.txt"
# The revolution with the most ground-truth objects (then the most misses and false ones).
frame="$(/usr/bin/python3 - "$DEMO/eval.json" <<'PY'
import json, sys
frames = json.load(open(sys.argv[1]))['frames']
best = max(frames, key=lambda f: (f['no'], f['mo'] + f['fo']))
print(best['frame'])
PY
)"
picture="$(ls "$DEMO"/*"_${frame//\//_}.png" 2>/dev/null | head -n 1 || true)"
[ -n "$picture" ] || picture="$(ls "$DEMO"/*.png | head -n 1)"
cp "$picture" "$OUT/demo.png"
echo
echo "demo: picture $OUT/demo.png (revolution $frame: ground truth left, detections right;"
echo "      class colours as in rviz, yellow boxes missed objects, red boxes false detections)"
echo "demo: every revolution's picture in $DEMO/, figures in $DEMO/eval.{txt,json}"
echo "      (the same call and figures as scripts/run eval's simulated drive)"
