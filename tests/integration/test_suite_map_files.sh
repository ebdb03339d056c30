#!/usr/bin/env bash
# Map files through the onboard/ground split (issue 11, item 4; docs/design.md "Map files"):
# rgbd-slam saves the room's map; then rgbd-mapper and rgbd-tracker both start from it
# (--load-map, the same --map-id) in the two namespaces of link.sh:
#   - localising only: the tracker poses >= 295 of the 300 frames at ATE <= 3 mm, in the
#     saved map's world frame (its first pose within 1 cm of the saving run's), adds no
#     keyframe, and applies the mapper's maps of the loaded map (none foreign);
#   - extending a map saved over the first half of the frames: the tracker adds keyframes
#     after the loaded ones over the second half, the mapper integrates and acknowledges
#     every one (its map holds the loaded keyframes and the new);
#   - bad uses end with status 2 and a clear error.
source "$(dirname "$0")/common.sh"
source "$(dirname "$0")/link.sh"
source "$(dirname "$0")/split.sh"
require_netns
seq=synth:room,frames=300
"$PROCS/rgbd-slam" --source "$seq" --deterministic --quiet --output "$WORK/saved.txt" --save-map "$WORK/room.map" \
    > "$WORK/save.out" 2> "$WORK/save.err" || fail "saving run failed: $(tail -5 "$WORK/save.err")"
echo "saved: $(split_value keyframes "$WORK/save.out") keyframes, $(split_value map_points "$WORK/save.out") points, $(stat -c %s "$WORK/room.map") bytes"
"$PROCS/rgbd-slam" --source synth:room,frames=150 --deterministic --quiet --output "$WORK/half.txt" --save-map "$WORK/half.map" \
    > "$WORK/half.out" 2> "$WORK/half.err" || fail "saving run (150 frames) failed: $(tail -5 "$WORK/half.err")"
half_keyframes=$(split_value keyframes "$WORK/half.out")

# Bad uses: each must fail on its arguments, before any LCM traffic; each still runs in a
# private namespace of its own (scripts/netns-run), so that a regression could not reach the
# host's interfaces.
expect_usage_error() {  # expect_usage_error TEXT PROC ARGS...
  local text=$1 proc=$2 status=0
  shift 2
  "$NETNS_RUN" "$PROCS/$proc" --camera "$SRC/config/cameras/synthetic.yaml" --lcm-url "$LCM_URL" "$@" \
      > /dev/null 2> "$WORK/bad.err" || status=$?
  [ "$status" -eq 2 ] || fail "$proc $*: expected status 2, got $status: $(cat "$WORK/bad.err")"
  grep -q -- "$text" "$WORK/bad.err" || fail "$proc $*: expected '$text': $(cat "$WORK/bad.err")"
  echo "refused as expected: $(head -1 "$WORK/bad.err")"
}
expect_usage_error "go together" rgbd-mapper --load-map "$WORK/room.map" --state-dir none
expect_usage_error "go together" rgbd-mapper --map-id 5 --state-dir none
expect_usage_error "needs --map-id" rgbd-tracker --load-map "$WORK/room.map"
expect_usage_error "needs --load-map" rgbd-tracker --localise-only
expect_usage_error "cannot open map file" rgbd-tracker --load-map "$WORK/missing.map" --map-id 5
head -c 5000 "$WORK/room.map" > "$WORK/cut.map"
expect_usage_error "truncated at byte 5000" rgbd-mapper --load-map "$WORK/cut.map" --map-id 5 --state-dir none
expect_usage_error "made in mode depth-ba" rgbd-tracker --load-map "$WORK/room.map" --map-id 5 --set slam.mode=mono
expect_usage_error "cannot write" rgbd-mapper --keyframes-out "$WORK/missing-dir/keyframes.txt" --state-dir none

link_up
# Localising only.
SPLIT_TRACKER_ARGS=(--load-map "$WORK/room.map" --localise-only)
split_start "$WORK/localise" 0 --load-map "$WORK/room.map" --map-id "$SPLIT_MAP_ID"
split_capture "$WORK/localise" "$seq"
split_finish "$WORK/localise"
split_report "$WORK/localise" "localise-only in the loaded map"
t=$WORK/localise/tracker.out
poses=$(tail -n +2 "$WORK/localise/trajectory.csv" | wc -l)
ate=$(split_value ate_rmse_m "$WORK/localise/eval.txt")
[ "$poses" -ge 295 ] || fail "localise-only: poses for $poses of 300 frames (< 295)"
awk -v a="$ate" 'BEGIN { exit !(a <= 0.003) }' || fail "localise-only: ATE $ate m > 3 mm"
[ "$(split_value keyframes "$t")" -eq 0 ] || fail "localise-only added keyframes: $(cat "$t")"
[ "$(split_value maps_foreign "$t")" -eq 0 ] || fail "the tracker refused the mapper's maps as foreign"
[ "$(split_value maps_applied "$t")" -gt 0 ] || fail "the tracker applied no map of the mapper's"
first_a=$(awk 'NR == 1 {print $2, $3, $4}' "$WORK/saved.txt")
first_b=$(grep -v '^#' "$WORK/localise/trajectory.txt" | awk 'NR == 1 {print $2, $3, $4}')
awk -v a="$first_a" -v b="$first_b" 'BEGIN { split(a, p); split(b, q);
  d = sqrt((p[1]-q[1])^2 + (p[2]-q[2])^2 + (p[3]-q[3])^2); exit !(d < 0.01) }' \
  || fail "not in the saved map's frame: first poses $first_a (saving run) and $first_b"

# Extending the first half's map: keyframe ids continue after the file's, and the mapper
# takes them.
SPLIT_TRACKER_ARGS=(--load-map "$WORK/half.map")
split_start "$WORK/extend" 0 --load-map "$WORK/half.map" --map-id "$SPLIT_MAP_ID"
split_capture "$WORK/extend" "$seq"
split_finish "$WORK/extend"
split_report "$WORK/extend" "extending the loaded map"
t=$WORK/extend/tracker.out
split_mapper_summary "$WORK/extend" > "$WORK/extend/mapper.summary"
added=$(split_value keyframes "$t")
mapper_keyframes=$(split_value mapper_keyframes "$WORK/extend/mapper.summary")
echo "extending: tracker added $added keyframes, the mapper holds $mapper_keyframes (loaded $half_keyframes)"
poses=$(tail -n +2 "$WORK/extend/trajectory.csv" | wc -l)
[ "$poses" -ge 295 ] || fail "extending: poses for $poses of 300 frames (< 295)"
[ "$added" -gt 0 ] || fail "extending: the tracker added no keyframe"
[ "$(split_value keyframes_unacked "$t")" -eq 0 ] || fail "extending: keyframes left unacknowledged"
mapper_culled=$(split_value mapper_culled "$WORK/extend/mapper.summary")
[ $((mapper_keyframes + mapper_culled)) -eq $((half_keyframes + added)) ] \
  || fail "the mapper holds $mapper_keyframes keyframes and culled $mapper_culled, expected $half_keyframes loaded + $added added"
ate=$(split_value ate_rmse_m "$WORK/extend/eval.txt")
awk -v a="$ate" 'BEGIN { exit !(a <= 0.003) }' || fail "extending: ATE $ate m > 3 mm"
echo "PASS"
