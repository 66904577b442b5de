#!/usr/bin/env bash
# Motion retrieval: index pose tracks by their motion codes, then find where a query's motion happens in them.
#   examples/search.sh [OPENPOSE_EXAMPLES] [OUT] [SIZE]
# OPENPOSE_EXAMPLES holds the OpenPose folders tall_man and small_man (at least 104 frames each); SIZE is their
# image size (OpenPose JSON stores none; the shipped weights do not depend on it, the authors' weights do).
set -euo pipefail
EXAMPLES=${1:-../shared/openpose_examples}
OUT=${2:-out/search}
SIZE=${3:-720x720}

# frames SRC DST FIRST END: OpenPose frames FIRST..END-1 of SRC copied into the folder DST (END empty: to the end).
# The reader numbers a folder's frames from its smallest frame number, so DST starts at SRC's frame FIRST.
frames() {
  mkdir -p "$2"
  find "$1" -maxdepth 1 -name '*_keypoints.json' | sort | sed -n "$(($3 + 1)),${4:-\$}p" | xargs -I{} cp {} "$2/"
}

# The collection: both examples, and tall_man again without its first 20 frames (a time-shifted copy).
frames "$EXAMPLES/tall_man" "$OUT/tracks/tall_man_shifted" 20 ""
clone search index "$EXAMPLES/tall_man" "$EXAMPLES/small_man" "$OUT/tracks" --out "$OUT/index.npz" --size "$SIZE"

# The query: 64 frames cut out of tall_man (frames 40..103). It is found in tall_man from frame 40, and in the
# shifted copy from frame 20; small_man walks differently and scores lower.
frames "$EXAMPLES/tall_man" "$OUT/query" 40 104
clone search query "$OUT/query" --index "$OUT/index.npz" --size "$SIZE" --top 3
clone search query "$OUT/query" --index "$OUT/index.npz" --size "$SIZE" --top 3 --json > "$OUT/hits.json"
echo "wrote $OUT/index.npz and $OUT/hits.json"
