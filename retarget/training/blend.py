"""Blend two retargeting checkpoints of one network: ``(1 - share) * A + share * B``, weight by weight.

    python -m retarget.training.blend A.pt B.pt --share 0.3 --out BLEND.pt

A weight average along the line between two fine-tunings of the same start (here: run 6's mean and run 7, which
fine-tuned it on turned motions) trades what each learnt; the shipped weights are such a blend
(retarget/weights/MODEL_CARD.md). The result keeps A's statistics and preprocessing and carries no training state.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pose_io.errors import InputError
from retarget.network.checkpoint import load_checkpoint, save_checkpoint


def blend_checkpoints(a: str | Path, b: str | Path, share: float, out: str | Path) -> Path:
    """Write ``(1 - share) * A + share * B`` to ``out`` (floating-point tensors; others are A's).

    Raises:
        InputError: ``share`` outside [0, 1], unreadable checkpoints, or two that are not the same network with
            the same input statistics.
    """
    if not 0.0 <= share <= 1.0:
        raise InputError(f"--share {share}: must lie in [0, 1]")
    first, second = load_checkpoint(a), load_checkpoint(b)
    if first.model.config != second.model.config:
        raise InputError(f"{a} and {b}: not the same network configuration")
    if not (np.array_equal(first.stats.mean, second.stats.mean) and np.array_equal(first.stats.std, second.stats.std)):
        raise InputError(f"{a} and {b}: different input statistics; a blend of them would read neither's inputs")
    theirs = second.model.state_dict()
    mixed = {k: (1.0 - share) * v + share * theirs[k] if v.is_floating_point() else v
             for k, v in first.model.state_dict().items()}  # fmt: skip
    first.model.load_state_dict(mixed)
    return save_checkpoint(out, first.model, first.stats, first.preprocess)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m retarget.training.blend", description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path, help="first checkpoint (its statistics and preprocessing are kept)")
    parser.add_argument("b", type=Path, help="second checkpoint")
    parser.add_argument("--share", type=float, required=True, help="weight of B, in [0, 1]")
    parser.add_argument("--out", type=Path, required=True, help="checkpoint to write (not A or B)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    args = parser.parse_args(argv)
    if args.out.resolve() in (args.a.resolve(), args.b.resolve()):
        parser.exit(2, "error: --out must not be one of the inputs\n")
    if args.out.exists() and not args.overwrite:
        parser.exit(2, f"error: --out {args.out} exists (pass --overwrite to replace it)\n")
    try:
        print(blend_checkpoints(args.a, args.b, args.share, args.out))
    except InputError as exc:
        parser.exit(2, f"error: {exc}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
