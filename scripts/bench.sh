#!/usr/bin/env bash
# Called by `scripts/run bench` (after setup + build): runs the benchmarks pinned to one core
# (taskset -c 0) and writes their output to results/.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WS="${UD_WS:-$REPO/.ws}"
BIN="$WS/devel/lib/urban_detection"
OUT="$REPO/results"
mkdir -p "$OUT"
pin() { if command -v taskset >/dev/null; then taskset -c 0 "$@"; else "$@"; fi; }

# Decoding of one 600 rpm revolution (348 packets, 133,632 returns), SZTAKI calibration from
# $UD_SHARED_DATA when present. Counters: median_ms, p95_ms, Mpoints_per_s_median.
pin "$BIN/urban_detection_bench_decode" --benchmark_repetitions=5 \
    --benchmark_out="$OUT/bench_decode.json" --benchmark_out_format=json "$@" \
  | tee "$OUT/bench_decode.txt"
