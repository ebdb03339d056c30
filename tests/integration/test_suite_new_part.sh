#!/usr/bin/env bash
# A new part of the map where the camera is lost in unmapped space (tracker.new_part_after_failures,
# docs/design.md "Map parts"), through the whole suite in a private network namespace
# (scripts/run-local), in real time: the corridor's camera covered for 5 s (frames 200-349)
# while it flies on 5 m into a stretch never mapped. Relocalisation cannot find it there; after
# the failed attempts rgbd-tracker starts a new part from a frame's depth (on its relocaliser
# thread), sends that keyframe flagged new_part, and tracks the rest of the corridor: at least
# 100 frames after the cover posed, rgbd-mapper starts the part (map_parts_started), every
# keyframe acknowledged. With the option at 0 the camera stays lost after the cover.
source "$(dirname "$0")/common.sh"
require_netns
seq=synth:corridor,frames=600,cover=200-349

value() { awk -v k="$1" '$1 == k {print $2}' "$2"; }
run() {  # run NAME NEW_PART_AFTER_FAILURES
  RGBDSLAM_BUILD_DIR=$BUILD "$SRC/scripts/run-local" --source "$seq" --rate 30 --out "$WORK/$1" \
      --tracker-arg --set --tracker-arg "tracker.new_part_after_failures=$2" > "$WORK/$1.out" 2>&1 \
    || fail "$1: run-local failed: $(tail -5 "$WORK/$1.out")"
  local tracker=$WORK/$1/rgbd-tracker.out mapper=$WORK/$1/rgbd-mapper.out
  local poses parts started keyframes acked
  poses=$(value poses "$tracker") parts=$(value new_parts "$tracker") started=$(value map_parts_started "$mapper")
  keyframes=$(value keyframes "$tracker") acked=$(value keyframes_acked "$tracker")
  echo "$1: $poses / 450 uncovered frames posed, $parts new parts (mapper: $started started," \
       "$(value map_parts_joined "$mapper") joined, $(value map_parts "$mapper") at the end), $acked / $keyframes keyframes acknowledged"
  [ "$keyframes" -gt 0 ] && [ "$acked" -eq "$keyframes" ] || fail "$1: $acked of $keyframes keyframes acknowledged"
  if [ "$2" -gt 0 ]; then
    [ "$parts" -ge 1 ] || fail "$1: no new part started"
    [ "$started" -ge 1 ] || fail "$1: the mapper started no part"
    [ "$poses" -ge 300 ] || fail "$1: only $poses frames posed: fewer than 100 after the cover"
  else
    [ "$parts" -eq 0 ] && [ "$started" -eq 0 ] || fail "$1: a new part with the option at 0"
    [ "$poses" -le 210 ] || fail "$1: $poses frames posed: the camera came back without a new part?"
  fi
}
run new_part 60
run never 0
echo "PASS"
