#!/usr/bin/env bash
# Every process, test tool and benchmark that links procs/common runs on jemalloc with its
# background purging on (procs/common/allocator.h): the link must take allocator.cpp even
# where a program calls nothing in it (procs/CMakeLists.txt, --undefined). Checked in each
# program as it runs: jemalloc's statistics at exit (MALLOC_CONF=stats_print:true, printed on
# stderr after --help) name the background threads that ran.
source "$(dirname "$0")/common.sh"
checked=0
for exe in "$PROCS"/* "$BUILD"/bench/bench_*; do
  [ -f "$exe" ] && [ -x "$exe" ] || continue
  stats=$(MALLOC_CONF=stats_print:true timeout 20 "$exe" --help 2>&1 >/dev/null) || true
  grep -Eq '^Background threads: [1-9]' <<< "$stats" \
    || fail "$(basename "$exe"): no jemalloc background thread ($(grep -m1 -E 'Background threads|jemalloc' <<< "$stats" || echo 'not on jemalloc'))"
  checked=$((checked + 1))
done
[ "$checked" -ge 7 ] || fail "only $checked programs found under $PROCS and $BUILD/bench"
echo "PASS: $checked programs on jemalloc with background purging"
