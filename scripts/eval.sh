#!/usr/bin/env bash
# F-rate evaluation (paper Sec. 5) of both detectors on every labelled dataset present:
# ../shared/data/kitti_object, ../shared/data/semantic_kitti (when the shared folder exists)
# and a simulated drive (always, once the simulator is built). Called by `scripts/run eval`
# after setup + build with the workspace sourced. Writes results/eval_<dataset>.{json,txt}
# (shipped configs, object classifier on) and results/eval_<dataset>_no_classifier.* (off)
# and prints a combined table. SemanticKITTI is what the shipped classifier was trained on, so
# there it is scored without the classifier (per sequence and pooled) and, with it, only
# leave-one-sequence-out (urban_detection_train_classifier, intensity features on and off:
# results/loso_semantic_kitti{,_no_intensity}.{json,txt}). Then the segmentation accuracy
# (urban_detection_seg_eval) on SemanticKITTI and the simulated drive into
# results/seg_eval_<dataset>.{json,txt}.
# Extra arguments go to every urban_detection_eval call
# (e.g. --details).
set -euo pipefail
# shellcheck source=tool_env.sh
source "$(dirname "${BASH_SOURCE[0]}")/tool_env.sh"  # REPO BIN DATA OUT PIN CONFIGS

if [ ! -x "$BIN/urban_detection_eval" ]; then
  echo "eval: $BIN/urban_detection_eval is not built" >&2
  exit 1
fi
ran=()
run() {
  local name="$1"; shift
  echo "== eval: $name"
  "${PIN[@]}" "$BIN/urban_detection_eval" "$@" --detector both "${CONFIGS[@]}" \
      --json "$OUT/eval_$name.json" "${EXTRA[@]}" | tee "$OUT/eval_$name.txt"
  ran+=("$OUT/eval_$name.json")
}
EXTRA=("$@")

if [ -d "$DATA/kitti_object/velodyne" ]; then
  run kitti_object --kitti-object "$DATA/kitti_object"
  run kitti_object_no_classifier --kitti-object "$DATA/kitti_object" --classifier off
else
  echo "== eval: skipping KITTI object (no $DATA/kitti_object)"
fi
if [ -d "$DATA/semantic_kitti" ]; then
  run semantic_kitti_no_classifier --semantic-kitti "$DATA/semantic_kitti" --classifier off
  for variant in "" _no_intensity; do
    echo "== eval: semantic_kitti leave-one-sequence-out$variant"
    flags=()
    [ -n "$variant" ] && flags=(--no-intensity)
    "${PIN[@]}" "$BIN/urban_detection_train_classifier" --semantic-kitti "$DATA/semantic_kitti" \
        "${CONFIGS[@]}" "${flags[@]}" --json "$OUT/loso_semantic_kitti$variant.json" \
        | tee "$OUT/loso_semantic_kitti$variant.txt"
  done
else
  echo "== eval: skipping SemanticKITTI (no $DATA/semantic_kitti)"
fi
if [ -x "$BIN/urban_detection_simulate" ]; then
  bash "$REPO/scripts/sim_drive.sh" "$OUT/sim"
  # 40 revolutions: the kd-tree baseline takes seconds per simulated revolution.
  run sim --sim "$OUT/sim/drive.gt" --pcap "$OUT/sim/drive.pcap" --max-frames 40
  run sim_no_classifier --sim "$OUT/sim/drive.gt" --pcap "$OUT/sim/drive.pcap" --max-frames 40 \
      --classifier off
  echo "== eval: tracking (CLEAR-MOT) on the whole simulated drive"
  "${PIN[@]}" "$BIN/urban_detection_eval" --tracking --sim "$OUT/sim/drive.gt" \
      --pcap "$OUT/sim/drive.pcap" "${CONFIGS[@]}" --tracker-config "$REPO/config/object_tracker.yaml" \
      --json "$OUT/tracking_sim.json" | tee "$OUT/tracking_sim.txt"
else
  echo "== eval: skipping the simulated drive (urban_detection_simulate not built)"
fi

[ "${#ran[@]}" -gt 0 ] || { echo "eval: no dataset found" >&2; exit 1; }

# Segmentation accuracy: ground / walls / foreground per point, Hough on and off.
SEG_CONFIG=()
[ -f "$REPO/config/segmentation.yaml" ] && SEG_CONFIG=(--config "$REPO/config/segmentation.yaml")
if [ -x "$BIN/urban_detection_seg_eval" ]; then
  if [ -d "$DATA/semantic_kitti/sequences/00/velodyne" ]; then
    echo "== seg_eval: semantic_kitti"
    "${PIN[@]}" "$BIN/urban_detection_seg_eval" "$DATA/semantic_kitti/sequences/00" \
        "${SEG_CONFIG[@]}" --json "$OUT/seg_eval_semantic_kitti.json" \
        | tee "$OUT/seg_eval_semantic_kitti.txt"
  fi
  if [ -s "$OUT/sim/drive.gt" ]; then
    echo "== seg_eval: sim"
    "${PIN[@]}" "$BIN/urban_detection_seg_eval" --sim "$OUT/sim/drive.gt" \
        --pcap "$OUT/sim/drive.pcap" "${SEG_CONFIG[@]}" --json "$OUT/seg_eval_sim.json" \
        | tee "$OUT/seg_eval_sim.txt"
  fi
fi
/usr/bin/python3 - "${ran[@]}" <<'PY' | tee "$OUT/eval_summary.txt"
import json, os, sys
print("\n%-30s %-18s %6s %5s %5s %5s %5s %9s %7s %7s" % (
    "dataset", "detector", "frames", "NO", "MO", "FO", "ign", "precision", "recall", "F-rate"))
for path in sys.argv[1:]:
    d = json.load(open(path))
    for name, s in d["by_detector"].items():
        print("%-30s %-18s %6d %5d %5d %5d %5d %9.3f %7.3f %7.3f" % (
            os.path.basename(path)[len("eval_"):-len(".json")], name, d["frames_evaluated"], s["no"], s["mo"], s["fo"], s["ignored"],
            s["precision"], s["recall"], s["f_rate"]))
print("paper (Table 1, overall): hierarchical grid F 0.83, kd-tree connected components F 0.72")
PY
