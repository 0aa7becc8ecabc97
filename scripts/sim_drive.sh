#!/usr/bin/env bash
# Writes the simulated demo drive (packets + ground truth) into DIR (default results/sim),
# unless it is already there and newer than the simulator. Used by eval.sh and bench.sh.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
BIN="$(ud_workspace "$REPO")/devel/lib/urban_detection"
DIR="${1:-$REPO/results/sim}"
mkdir -p "$DIR"
SIM="$BIN/urban_detection_simulate"
if [ -s "$DIR/drive.pcap" ] && [ -s "$DIR/drive.gt" ] && [ "$DIR/drive.gt" -nt "$SIM" ] \
    && [ "$DIR/drive.gt" -nt "$REPO/config/demo_drive.yaml" ]; then
  echo "== sim: reusing $DIR/drive.{pcap,gt}"
  exit 0
fi
echo "== sim: simulating the demo drive (config/demo_drive.yaml) into $DIR"
"$SIM" --config "$REPO/config/demo_drive.yaml" --pcap "$DIR/drive.pcap" --gt "$DIR/drive.gt"
