#!/usr/bin/env bash
# A generator prior from synthetic performers (licence-clean: CMU motions on the project's own characters):
# each performer trains `clone train-ref` for MINUTES from the model of the one before (--init), so the last
# model has seen every character, outfit, view and motion of the list. Re-running skips the performers whose
# model is already there (delete OUT/mN.pt to train N again).
#
#   scripts/train_generator_prior.sh [OUT] [MINUTES]      # default /tmp/clone2d-prior, 2 minutes each
#   clone train-ref REF.mp4 --init OUT/m5.pt ...          # start a reference model from it
#
# Needs ../shared/mocap (the CMU clips); the result is not shipped (see docs/cloning.md for what it measured).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
clone="${CLONE:-$here/.venv/bin/clone}"
out="${1:-/tmp/clone2d-prior}"
minutes="${2:-2}"
mocap="$here/../shared/mocap/cmu_iclone/subjects"
[ -d "$mocap" ] || { echo "error: no CMU motions in $mocap" >&2; exit 2; }
mkdir -p "$out"
# character, CMU clip (subject_trial), view yaw in degrees
performers=(
  "average 005_04 0"
  "long_arms 005_07 -30"
  "tall_long_legs 002_01 45"
  "child 005_09 15"
  "short_stocky 006_03 -15"
  "7 005_12 0"
)
prev=none
i=0
for spec in "${performers[@]}"; do
  read -r character clip yaw <<< "$spec"
  frames="$out/r$i"
  model="$out/m$i.pt"
  if [ ! -f "$model" ]; then
    [ -d "$frames" ] || "$clone" synth render "$mocap/${clip%%_*}/$clip.bvh.gz" --out "$frames" \
      --character "$character" --yaw "$yaw" > /dev/null
    "$clone" train-ref "$frames/poses.npz" "$frames/frames" --size 256 --minutes "$minutes" --init "$prev" \
      --out "$model" --device cpu
  fi
  prev="$model"
  i=$((i + 1))
done
echo "prior: $prev"
