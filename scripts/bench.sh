#!/usr/bin/env bash
# Speed of the core pipeline, pinned to one core: ../shared/data/kitti_raw (both drives, one
# run) when the shared folder exists, and a simulated drive's packets (always, once the
# simulator is built). Called by `scripts/run bench` after setup + build with the workspace
# sourced. Also runs the packet decoder's own micro-benchmark (urban_detection_bench_decode).
# Writes results/bench_<dataset>.{json,txt} and prints a combined table. Extra arguments go to
# every urban_detection_bench call (e.g. --repeat 5).
set -euo pipefail
# shellcheck source=tool_env.sh
source "$(dirname "${BASH_SOURCE[0]}")/tool_env.sh"  # REPO BIN DATA OUT PIN CONFIGS
EXTRA=("$@")

# Packet decoding alone (Google Benchmark, urban_detection_bench_decode): one 600 rpm
# revolution (348 packets, 133,632 returns), SZTAKI calibration from $UD_SHARED_DATA when
# present. Counters: median_ms, p95_ms, Mpoints_per_s_median.
if [ -x "$BIN/urban_detection_bench_decode" ]; then
  echo "== bench: packet decoding (urban_detection_bench_decode)"
  "${PIN[@]}" "$BIN/urban_detection_bench_decode" --benchmark_repetitions=5 \
      --benchmark_out="$OUT/bench_decode.json" --benchmark_out_format=json \
    | tee "$OUT/bench_decode.txt"
fi

# Simulation of one revolution of the default drive (urban_detection_bench_simulation:
# config/demo_drive.yaml, nominal S2, at 600/300/1200 rpm): ray casting, noise, packet encoding,
# ground truth. One revolution per repetition: the aggregates are median and p95 per revolution.
if [ -x "$BIN/urban_detection_bench_simulation" ]; then
  echo "== bench: simulated HDL-64E drive (urban_detection_bench_simulation)"
  "${PIN[@]}" "$BIN/urban_detection_bench_simulation" \
      --benchmark_out="$OUT/bench_simulation.json" --benchmark_out_format=json \
    | tee "$OUT/bench_simulation.txt"
fi

if [ ! -x "$BIN/urban_detection_bench" ]; then
  echo "bench: $BIN/urban_detection_bench is not built" >&2
  exit 1
fi
ran=()
run() {
  local name="$1"; shift
  echo "== bench: $name"
  "${PIN[@]}" "$BIN/urban_detection_bench" "$@" --label "$name" "${CONFIGS[@]}" \
      --json "$OUT/bench_$name.json" "${EXTRA[@]}" | tee "$OUT/bench_$name.txt"
  ran+=("$OUT/bench_$name.json")
}

raw=()
for d in "$DATA"/kitti_raw/drive_*; do [ -d "$d" ] && raw+=(--pcd-dir "$d"); done
if [ "${#raw[@]}" -gt 0 ]; then
  run kitti_raw "${raw[@]}"
else
  echo "== bench: skipping kitti_raw (no $DATA/kitti_raw)"
fi
if [ -x "$BIN/urban_detection_simulate" ]; then
  bash "$REPO/scripts/sim_drive.sh" "$OUT/sim"
  # Packets -> objects on the simulated drive. No kd-tree here: the baseline takes seconds per
  # simulated revolution (dense near-range blobs); the speed-up is measured on kitti_raw.
  run sim --pcap "$OUT/sim/drive.pcap" --no-kdtree
else
  echo "== bench: skipping the simulated drive (urban_detection_simulate not built)"
fi

[ "${#ran[@]}" -gt 0 ] || { echo "bench: no dataset found" >&2; exit 1; }
/usr/bin/python3 - "${ran[@]}" <<'PY' | tee "$OUT/bench_summary.txt"
import json, sys
runs = [json.load(open(p)) for p in sys.argv[1:]]
stages = []
for r in runs:
    for s in r["stages"]:
        if s not in stages:
            stages.append(s)
w = 36
print("\n%-*s" % (w, "wall median / p95 (cpu median) ms") +
      "".join("%30s" % r["label"] for r in runs))
for s in stages:
    row = "%-*s" % (w, s)
    for r in runs:
        v = r["stages"].get(s)
        row += "%30s" % ("-" if v is None else "%.2f / %.2f (%.2f)" % (
            v["median_ms"], v["p95_ms"], v["cpu_median_ms"]))
    print(row)
for key, fmt in (("pipeline_median_ms", "%.2f"), ("pipeline_cpu_median_ms", "%.2f"),
                 ("pipeline_fps", "%.1f"), ("pipeline_cpu_fps", "%.1f"),
                 ("hier_vs_kdtree_speedup", "%.1f"),
                 ("hier_vs_kdtree_pcl_default_speedup", "%.1f"), ("peak_rss_mb", "%.0f"),
                 ("revolutions", "%d"), ("mean_points", "%.0f"),
                 ("mean_foreground_points", "%.0f")):
    print("%-*s" % (w, key) + "".join(
        "%30s" % ("-" if r.get(key) is None else fmt % r[key]) for r in runs))
print("pipeline = %s; paper: 28 fps hierarchical grid, 0.35 fps kd-tree" %
      ", ".join("%s %s" % (r["label"], "packets->objects" if r["pipeline_includes_packet_decode"]
                           else "cloud->objects") for r in runs))
PY
