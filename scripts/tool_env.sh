# Sourced by the measuring scripts (bench.sh, eval.sh): where things are and how they run.
#   REPO     the checkout
#   BIN      the built tools (<workspace>/devel/lib/urban_detection, scripts/workspace.sh)
#   DATA     the shared datasets (UD_SHARED_DATA, default ../shared/data)
#   OUT      results/, created
#   PIN      the command prefix pinning a tool to core 0 (empty without taskset)
#   CONFIGS  --config FILE for each of config/{segmentation,hierarchical_grid,kdtree,classification}.yaml
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
BIN="$(ud_workspace "$REPO")/devel/lib/urban_detection"
DATA="${UD_SHARED_DATA:-$REPO/../shared/data}"
OUT="$REPO/results"
mkdir -p "$OUT"

PIN=()
if command -v taskset >/dev/null; then PIN=(taskset -c 0); else
  echo "$(basename "$0"): taskset not found, running unpinned" >&2; fi
CONFIGS=()
for c in segmentation hierarchical_grid kdtree classification; do
  [ -f "$REPO/config/$c.yaml" ] && CONFIGS+=(--config "$REPO/config/$c.yaml")
done
