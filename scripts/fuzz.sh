#!/usr/bin/env bash
# libFuzzer targets of test/fuzz: builds them with clang (ASan + UBSan + libFuzzer)
# in a build directory of their own beside the catkin workspace, then runs each target for
# the given number of seconds (default 600), one after the other, niced.
#   scripts/run fuzz [seconds] [target ...]     e.g. scripts/run fuzz 30 fuzz_pcap_reader
#   scripts/run fuzz seeds                      rewrite the seed corpora (test/fuzz/make_seeds.cpp)
# Called by `scripts/run fuzz` after setup + the normal build (fuzz_velodyne_scan takes the
# generated message headers from $UD_WS/devel/include). Seeds: test/fuzz/corpus/<target>/
# (read only; crash-* files there are fixed findings replayed as regressions), dictionary
# test/fuzz/<target>.dict when present; inputs found while fuzzing go to <build>/corpus/<target>/, crashes, leaks and
# sanitizer reports to <build>/artifacts/ with the log in <build>/logs/<target>.log.
# Exit status: 0 when every target ran clean, 1 otherwise.
# Environment: UD_WS, UD_JOBS, UD_FUZZ_BUILD (default $UD_WS-fuzz), CXX_FUZZ (clang++).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=scripts/workspace.sh
source "$REPO/scripts/workspace.sh"
WS="$(ud_workspace "$REPO")"
BUILD="${UD_FUZZ_BUILD:-$WS-fuzz}"
JOBS="${UD_JOBS:-$(nproc)}"
SECONDS_PER_TARGET="${1:-600}"
shift || true
CXX_FUZZ="${CXX_FUZZ:-$(command -v clang++-14 || command -v clang++ || true)}"
CC_FUZZ="${CC_FUZZ:-$(command -v clang-14 || command -v clang || true)}"
[ -n "$CXX_FUZZ" ] || { echo "fuzz: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 1; }

log() { printf '[fuzz] %s\n' "$*" >&2; }

mkdir -p "$BUILD"
log "build: $BUILD ($CXX_FUZZ, $JOBS jobs)"
if ! { cmake -S "$REPO/test/fuzz" -B "$BUILD" -DCMAKE_C_COMPILER="$CC_FUZZ" \
         -DCMAKE_CXX_COMPILER="$CXX_FUZZ" -DUD_MSG_INCLUDE_DIR="$WS/devel/include" \
       && cmake --build "$BUILD" -j "$JOBS"; } >"$BUILD/build.log" 2>&1; then
  tail -n 40 "$BUILD/build.log"
  log "build failed (full log: $BUILD/build.log)"
  exit 1
fi

if [ "$SECONDS_PER_TARGET" = seeds ]; then
  "$BUILD/make_seeds" "$REPO/test/fuzz/corpus"
  log "seeds written to $REPO/test/fuzz/corpus"
  exit 0
fi
[[ "$SECONDS_PER_TARGET" =~ ^[0-9]+$ ]] || { log "usage: fuzz.sh [seconds|seeds] [target ...]"; exit 2; }

TARGETS=("$@")
if [ "${#TARGETS[@]}" -eq 0 ]; then
  for exe in "$BUILD"/fuzz_*; do [ -x "$exe" ] && TARGETS+=("$(basename "$exe")"); done
fi
[ "${#TARGETS[@]}" -gt 0 ] || { log "no fuzz targets built"; exit 1; }

mkdir -p "$BUILD/logs" "$BUILD/artifacts"
failed=0
summary=()
for t in "${TARGETS[@]}"; do
  exe="$BUILD/$t"
  [ -x "$exe" ] || { log "$t: not built"; failed=1; summary+=("$t  NOT BUILT"); continue; }
  seeds="$REPO/test/fuzz/corpus/$t"
  work="$BUILD/corpus/$t"
  mkdir -p "$work"
  dirs=("$work")
  [ -d "$seeds" ] && dirs+=("$seeds")
  extra=()
  [ -f "$REPO/test/fuzz/$t.dict" ] && extra+=(-dict="$REPO/test/fuzz/$t.dict")
  log "$t: ${SECONDS_PER_TARGET} s"
  rc=0
  # -timeout: one input taking 25 s is a hang; rss_limit: 2 GB is a leak or a blow-up.
  ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}" \
  UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}" \
    nice -n 10 "$exe" -max_total_time="$SECONDS_PER_TARGET" -timeout=25 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$BUILD/artifacts/$t-" "${extra[@]}" "${dirs[@]}" \
      >"$BUILD/logs/$t.log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$BUILD/logs/$t.log" | tail -n 1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$BUILD/logs/$t.log" | tail -n 1)
  cov=$(grep -oE 'cov: [0-9]+' "$BUILD/logs/$t.log" | tail -n 1 || true)
  if [ "$rc" -ne 0 ] || grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:' \
       "$BUILD/logs/$t.log"; then
    failed=1
    summary+=("$(printf '%-24s FAILED (exit %s) after %s executions; see %s' "$t" "$rc" "${execs:-?}" "$BUILD/logs/$t.log")")
    grep -E 'ERROR:|runtime error:|invariant violated|Test unit written|SUMMARY' "$BUILD/logs/$t.log" | head -n 8 >&2 || true
  else
    summary+=("$(printf '%-24s ok  %5s s  %10s executions  %6s exec/s  %s' "$t" "$SECONDS_PER_TARGET" "${execs:-?}" "${rate:-?}" "$cov")")
  fi
done
printf '%s\n' "== fuzz summary (${SECONDS_PER_TARGET} s per target)" "${summary[@]}"
exit "$failed"
