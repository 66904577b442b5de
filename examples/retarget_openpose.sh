#!/usr/bin/env bash
# Move one person's motion (an OpenPose track) onto another person's body proportions and camera view.
#   examples/retarget_openpose.sh [MOTION] [REFERENCE] [OUT]
set -euo pipefail
MOTION=${1:-../shared/openpose_examples/tall_man}
REFERENCE=${2:-../shared/openpose_examples/small_man}
OUT=${3:-out/retarget_openpose}

clone pose info "$MOTION"
clone pose info "$REFERENCE"
# The result is in the reference's frame; .npz keeps joints that leave the image (OpenPose JSON cannot).
clone retarget apply "$MOTION" --skeleton "$REFERENCE" --out "$OUT/retargeted.npz" --preview "$OUT/retargeted.mp4"
clone pose show "$REFERENCE" --out "$OUT/reference.mp4"
echo "wrote $OUT/retargeted.npz and $OUT/retargeted.mp4"
