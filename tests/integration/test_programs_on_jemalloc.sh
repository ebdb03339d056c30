#!/usr/bin/env bash
# Every process and benchmark runs on jemalloc with its background purging on
# (procs/common/allocator.h): the link must take allocator.cpp even where a program calls
# nothing in it (procs/CMakeLists.txt, --undefined). Checked in each program as it runs:
# jemalloc's statistics at exit (MALLOC_CONF=stats_print:true, printed on stderr after
# --help) count the background threads started. The environment also says
# background_thread:false (over any /etc/malloc.conf), so a thread counted was started by the
# program itself.
source "$(dirname "$0")/common.sh"
[ -x "$PROCS/rgbd-tracker" ] || skip "the processes are not built here (an instrumented build)"
checked=0
for exe in "$PROCS"/* "$BUILD"/bench/bench_*; do
  [ -f "$exe" ] && [ -x "$exe" ] || continue
  status=0
  stats=$(MALLOC_CONF=stats_print:true,background_thread:false timeout 20 "$exe" --help 2>&1 >/dev/null) || status=$?
  [ "$status" -ne 124 ] || fail "$(basename "$exe") --help did not end within 20 s"
  grep -Eq '^Background threads: [1-9]' <<< "$stats" \
    || fail "$(basename "$exe"): no jemalloc background thread started ($(grep -m1 -E 'Background threads' <<< "$stats" || echo 'no jemalloc statistics: not on jemalloc'))"
  checked=$((checked + 1))
done
[ "$checked" -ge 7 ] || fail "only $checked programs found under $PROCS and $BUILD/bench"
echo "PASS: $checked programs on jemalloc with background purging"
