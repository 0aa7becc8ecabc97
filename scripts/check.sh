#!/usr/bin/env bash
# Reliability check, run by CI after the normal tests:
#   1. test_core and test_ros built with AddressSanitizer + UndefinedBehaviorSanitizer
#      (CMake option UD_SANITIZE, gcc, -O1, assertions on) in a workspace of their own
#      ($UD_WS-asan), then run; any sanitizer report or failed test fails the check;
#   2. every libFuzzer target for [seconds] (default 30) each: scripts/fuzz.sh.
#   scripts/run check [seconds]
# Needs the normal workspace built first (fuzz_velodyne_scan reads its generated headers).
# Fits in ~15 min on 2 cores from a fresh clone (two builds of the core + 6 x 30 s).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
WS="$(ud_workspace "$REPO")"
ASAN_WS="${UD_ASAN_WS:-$WS-asan}"
JOBS="${UD_JOBS:-$(nproc)}"
FUZZ_SECONDS="${1:-30}"
export PATH="/usr/bin:/bin:/usr/sbin:/sbin:$PATH"
log() { printf '[check] %s\n' "$*" >&2; }
start=$(date +%s)

# ---- 1. sanitizer gtests
mkdir -p "$ASAN_WS/src"
[ -L "$ASAN_WS/src/urban_detection" ] || ln -sfn "$REPO" "$ASAN_WS/src/urban_detection"
log "sanitizer build: $ASAN_WS (ASan + UBSan, $JOBS jobs)"
if ! (cd "$ASAN_WS" && catkin_make -j"$JOBS" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" \
        -DUD_SANITIZE=ON -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON \
        test_core test_ros) >"$ASAN_WS/build.log" 2>&1; then
  tail -n 40 "$ASAN_WS/build.log"; log "sanitizer build failed (log: $ASAN_WS/build.log)"; exit 1
fi
set +u; source "$ASAN_WS/devel/setup.bash"; set -u
export ROS_HOME="${ROS_HOME:-$ASAN_WS/ros_home}"
export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$REPO/test/sanitizers/lsan.supp:print_suppressions=0"
failed=0
for t in test_core test_ros; do
  exe="$ASAN_WS/devel/lib/urban_detection/$t"
  [ -x "$exe" ] || { log "$t: not built"; failed=1; continue; }
  rc=0
  "$exe" --gtest_output="xml:$ASAN_WS/$t.xml" >"$ASAN_WS/$t.log" 2>&1 || rc=$?
  if [ "$rc" -ne 0 ] || grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer)|runtime error:' "$ASAN_WS/$t.log"; then
    failed=1
    grep -E 'FAILED|ERROR:|runtime error:|SUMMARY' "$ASAN_WS/$t.log" | head -n 20 >&2 || true
    log "$t: FAILED under ASan/UBSan (exit $rc, log: $ASAN_WS/$t.log)"
  else
    log "$t: clean under ASan/UBSan ($(grep -E '^\[  PASSED  \]' "$ASAN_WS/$t.log" | head -n 1))"
  fi
done
log "sanitizer part: $(( $(date +%s) - start )) s"

# ---- 2. fuzz targets
UD_WS="$WS" bash "$REPO/scripts/fuzz.sh" "$FUZZ_SECONDS" || failed=1
log "total: $(( $(date +%s) - start )) s"
if [ "$failed" -ne 0 ]; then log "check: FAILED"; exit 1; fi
log "check: ok"
