#!/usr/bin/env bash
# Map files on real data (../shared/data/tum_fr3_teddy_200; fails in CI when the data is
# missing, skips elsewhere): a run saves its map, a second run over the same frames
# localises in it with --localise-only, posing nearly every frame, adding no keyframe.
# Measured: see the README's table of commands.
source "$(dirname "$0")/common.sh"
DATA=$(require_shared_data tum_fr3_teddy_200)
ATE_BOUND_M=0.008
MIN_POSES=190
localise_in_saved_map "$MIN_POSES" "$ATE_BOUND_M" --source "tum:$DATA" \
    --camera "$SRC/config/cameras/tum_fr3.yaml" --deterministic --quiet
echo "PASS"
