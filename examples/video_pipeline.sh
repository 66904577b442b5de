#!/usr/bin/env bash
# From two videos to a cloned performance: the reference person is re-rendered doing the driver's motion.
#   examples/video_pipeline.sh REF_VIDEO DRIVER_VIDEO [OUT] [MINUTES]
# Needs the `extract` extra (MediaPipe): see the README.
set -euo pipefail
REF_VIDEO=$1
DRIVER_VIDEO=$2
OUT=${3:-out/video_pipeline}
MINUTES=${4:-5}

clone pose extract "$REF_VIDEO" --out "$OUT/reference"     # poses/ (OpenPose JSON) + frames/
clone pose extract "$DRIVER_VIDEO" --out "$OUT/driver"
clone train-ref "$OUT/reference/poses" "$OUT/reference/frames" --out "$OUT/ref_model.pt" --minutes "$MINUTES"
clone drive "$OUT/driver/poses" --model "$OUT/ref_model.pt" --out "$OUT/result.mp4" --side-by-side
clone report "$OUT/driver/poses" --model "$OUT/ref_model.pt" --out "$OUT/report"
echo "open $OUT/report/report.html"
