"""Stage `retarget`: the retargeting network on a 120-frame clip and a 10,000-frame track.

Ours: ``load_retargeter(...).retarget(...)`` (windows of 256 frames, 8 at a time, under inference mode),
timed end to end (pre-processing, network, integration, smoothing) and network only (``_decode_track``).
Baseline: the plain way the authors' scripts run it: eager fp32 with autograd on, the whole track as one
sequence through encode + decode, network only (so the baseline is not charged for our pre/post-processing).
"""

from __future__ import annotations

from typing import Any

import torch

from bench.data import source_track, tiled
from bench.harness import row, time_call


def _plain_forward(retargeter: Any, x: torch.Tensor, codes: Any) -> torch.Tensor:
    """[1, 30, T] -> [1, 30, T8]: one pass over the whole (padded) track with autograd on."""
    from retarget.api import _pad_to_multiple

    model = retargeter.model
    padded, _ = _pad_to_multiple(x, model.config.downsampling)  # [1, 30, T8]
    with torch.enable_grad():
        return model.decode(model.encode_motion(padded), retargeter._code_tensor(codes.body),
                            retargeter._code_tensor(codes.view))


def run(quick: bool = False, **_: object) -> dict[str, Any]:
    from retarget.api import PACKAGED_WEIGHTS, load_retargeter

    torch.set_num_threads(1)
    retargeter = load_retargeter(PACKAGED_WEIGHTS, device="cpu")
    source, origin = source_track()
    clip = tiled(source, 120)
    codes = retargeter.reference_codes(clip)
    rows = []
    cases = [("clip 120 frames", 120, 7, 0.3), ("track 10,000 frames", 2_000 if quick else 10_000, 3, 0.0)]
    for case, frames, repeats, min_time in cases:
        track = tiled(source, frames)
        x = retargeter._input(track, "bench track")  # [1, 30, T]
        if quick:
            repeats = max(2, repeats // 2)
        base = time_call(lambda x=x: _plain_forward(retargeter, x, codes), repeats, 1, min_time)
        net = time_call(lambda x=x: retargeter._decode_track(x, codes), repeats, 1, min_time)
        api = time_call(lambda t=track: retargeter.retarget(t, codes), repeats, 1, min_time)
        diff = float((_plain_forward(retargeter, x, codes)[..., : x.shape[-1]].detach()
                      - retargeter._decode_track(x, codes)).abs().max()) if frames <= 256 else None
        plain = "eager fp32, autograd on, whole track in one pass (network only)"
        case = case if frames != 2_000 else "track 2,000 frames (--quick)"
        rows.append(row(case, "ours: windowed, inference mode (network only)", net.rate(frames), "frames/s", base.rate(frames), plain, max_abs_diff=diff))
        rows.append(row(case, "ours: retarget() end to end", api.rate(frames), "frames/s", base.rate(frames), plain))
    return {
        "rows": rows,
        "notes": [
            f"input: {origin}, tiled forwards-backwards to the length; weights {PACKAGED_WEIGHTS.name}; 1 thread",
            "end to end includes body15 conversion, normalisation, root integration, smoothing and placement",
            "max_abs_diff: network outputs of ours vs plain on the clip (one window, so they must agree)",
        ],
    }
