#!/usr/bin/env bash
# Latent interpolation (paper Fig. 1): blend two clips' codes on a grid, two attributes at a time.
#   examples/interpolate.sh [A] [B] [OUT]
set -euo pipefail
A=${1:-../shared/openpose_examples/tall_man}
B=${2:-../shared/openpose_examples/small_man}
OUT=${3:-out/interpolate}

# Rows blend A's motion into B's, columns A's view into B's; every cell keeps A's skeleton.
clone retarget interpolate "$A" "$B" --vary motion,view --steps 5 --out "$OUT/motion_view.mp4"
# A's motion throughout, its body and view turning into B's; the poses as [5, 5, T, 15, 2] in A's pixels.
clone retarget interpolate "$A" "$B" --vary body,view --steps 5 --out "$OUT/body_view.npz"
python - "$OUT/body_view.npz" <<'PY'
import sys

import numpy as np

grid = np.load(sys.argv[1])
print(f"{sys.argv[1]}: poses {grid['poses'].shape}, rows {grid['rows']}, columns {grid['cols']}, {grid['kept']} of A")
PY
echo "wrote $OUT/motion_view.mp4 and $OUT/body_view.npz"
