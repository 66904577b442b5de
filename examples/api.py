"""The Python API in a plain script: read two tracks, retarget one onto the other, measure, write, draw.

    python examples/api.py MOTION_POSES REFERENCE_POSES OUT_DIR
"""

from __future__ import annotations

import sys
from pathlib import Path

from pose_io import fill_gaps, read_track, smooth, write_track
from pose_io.measures import proportion_error
from pose_io.video_out import write_pose_video
from retarget.api import load_retargeter
from retarget.baselines.methods import global_scale_retarget


def main(motion_path: str, reference_path: str, out_dir: str) -> None:
    out = Path(out_dir)
    motion, report = fill_gaps(read_track(motion_path), max_gap=5)
    print(f"motion: {motion.num_frames} frames at {motion.fps:g} fps; {report.summary()}")
    reference = smooth(read_track(reference_path).to_layout("body15"), sigma=1.0)

    retargeter = load_retargeter()  # the weights shipped in the package
    codes = retargeter.reference_codes(reference)  # skeleton, view and placement of the whole reference track
    moved = retargeter.retarget(motion, codes)  # body15, the reference's pixels, as many frames as the motion
    scaled = global_scale_retarget(motion.to_layout("body15"), reference)

    print(f"proportion error vs the reference: retargeted {proportion_error(moved.joints, reference.joints, 'body15'):.1f} %, "
          f"global scaling {proportion_error(scaled.joints, reference.joints, 'body15'):.1f} %, "
          f"driver as it is {proportion_error(motion.to_layout('body15').joints, reference.joints, 'body15'):.1f} % of height")
    write_track(moved, out / "retargeted.npz", overwrite=True)
    write_pose_video(moved, out / "retargeted.mp4", overwrite=True)
    print(f"wrote {out / 'retargeted.npz'} and {out / 'retargeted.mp4'}")


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
