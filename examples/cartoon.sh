#!/usr/bin/env bash
# Video-driven cartoons (paper Sec. 7): a character with exaggerated proportions performs a driver's motion.
#   examples/cartoon.sh [DRIVER] [OUT] [SIZE]
set -euo pipefail
DRIVER=${1:-../shared/openpose_examples/tall_man}
OUT=${2:-out/cartoon}
SIZE=${3:-720x720}  # OpenPose JSON stores no image size; the authors treat their examples as 720 x 720

mkdir -p "$OUT"
# A preset, seen as the driver is seen; the measures go next to the video (bighead.json).
clone cartoon "$DRIVER" --character bighead --size "$SIZE" --out "$OUT/bighead.mp4"
# Your own character: factors on a standard body's parts, seen from 30 degrees to its left.
cat > "$OUT/longlegs.character.json" <<'JSON'
{"name": "longlegs", "legs": 1.5, "torso": 0.8, "head": 1.3}
JSON
clone cartoon "$DRIVER" --character "$OUT/longlegs.character.json" --yaw 30 --size "$SIZE" --out "$OUT/longlegs.mp4" \
    --poses "$OUT/longlegs_poses.npz"
echo "wrote $OUT/bighead.mp4 (+ .json) and $OUT/longlegs.mp4 (+ .json, poses)"
