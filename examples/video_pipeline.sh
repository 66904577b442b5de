#!/usr/bin/env bash
# From two videos to a cloned performance: the reference person is re-rendered doing the driver's motion.
#   examples/video_pipeline.sh REF_VIDEO DRIVER_VIDEO [OUT] [MINUTES]
# Needs the `extract` extra (MediaPipe): see the README. Poses are extracted once per video and cached.
set -euo pipefail
REF_VIDEO=$1
DRIVER_VIDEO=$2
OUT=${3:-out/video_pipeline}
MINUTES=${4:-5}

clone train-ref "$REF_VIDEO" --out "$OUT/ref_model.pt" --minutes "$MINUTES"
clone drive "$DRIVER_VIDEO" --model "$OUT/ref_model.pt" --out "$OUT/result.mp4" --side-by-side
clone report "$DRIVER_VIDEO" --model "$OUT/ref_model.pt" --out "$OUT/report"
echo "open $OUT/report/report.html"
