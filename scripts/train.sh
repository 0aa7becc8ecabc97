#!/usr/bin/env bash
# Rebuilds the shipped object classifier, config/object_classifier.yml.gz, bit for bit: the
# pipeline with the shipped configs over the SemanticKITTI scans (all ten sequences), a random
# forest with the tool's fixed defaults and seed, its P(object) threshold chosen on the
# leave-one-sequence-out predictions. Called by `scripts/run train` after setup + build with the
# workspace sourced. Also writes the feature table and the leave-one-sequence-out report
# (results/train_classifier.{csv,json,txt}). Extra arguments go to the tool (e.g. --trees 64),
# which then no longer reproduces the shipped file.
set -euo pipefail
# shellcheck source=tool_env.sh
source "$(dirname "${BASH_SOURCE[0]}")/tool_env.sh"  # REPO BIN DATA OUT PIN CONFIGS

if [ ! -d "$DATA/semantic_kitti" ]; then
  echo "train: no SemanticKITTI scans in $DATA/semantic_kitti (set UD_SHARED_DATA)" >&2
  exit 1
fi
"${PIN[@]}" "$BIN/urban_detection_train_classifier" --semantic-kitti "$DATA/semantic_kitti" \
    "${CONFIGS[@]}" --out "$REPO/config/object_classifier.yml.gz" \
    --csv "$OUT/train_classifier.csv" --json "$OUT/train_classifier.json" "$@" \
    | tee "$OUT/train_classifier.txt"
sha256sum "$REPO/config/object_classifier.yml.gz"
