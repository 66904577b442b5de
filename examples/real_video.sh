#!/usr/bin/env bash
# The whole workflow on real people: a fashion model (the reference) performs a home dancer's moves, with the
# dance's music. Uses the research-only test videos of the project's shared folder; skips when it is absent.
#   examples/real_video.sh [REAL_DIR] [OUT] [MINUTES] [SIZE]
# REAL_DIR holds ubc_91BjuE6irxS.mp4 (reference) and dance_musepose.mp4 (driver); default ../shared/real.
set -euo pipefail
REAL=${1:-"$(dirname "$0")/../../shared/real"}
OUT=${2:-out/real_video}
MINUTES=${3:-10}
SIZE=${4:-256}
REF="$REAL/ubc_91BjuE6irxS.mp4"
DRIVER="$REAL/dance_musepose.mp4"
if [[ ! -f "$REF" || ! -f "$DRIVER" ]]; then
    echo "skipped: $REAL does not hold ubc_91BjuE6irxS.mp4 and dance_musepose.mp4"
    exit 0
fi

clone train-ref "$REF" --out "$OUT/ref_model.pt" --size "$SIZE" --minutes "$MINUTES"
clone drive "$DRIVER" --model "$OUT/ref_model.pt" --out "$OUT/dance.mp4"           # with the dance's music
clone drive "$DRIVER" --model "$OUT/ref_model.pt" --out "$OUT/dance_global_scale.mp4" --method global-scale
clone report "$DRIVER" --model "$OUT/ref_model.pt" --out "$OUT/report"
echo "open $OUT/report/report.html"
