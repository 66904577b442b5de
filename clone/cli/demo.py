"""`clone demo`: the whole pipeline on the built-in synthetic example."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import DEVICE_HELP, console, user_errors


@user_errors
def demo_command(
    out: Annotated[Path, typer.Option("--out", help="Output folder (a folder an earlier demo made is replaced).")] = Path(
        "demo_out"
    ),
    quick: Annotated[bool, typer.Option("--quick", help="Smaller videos and a shorter training budget.")] = False,
    minutes: Annotated[
        float | None, typer.Option("--minutes", min=0.1, help="Training budget of the reference model.")
    ] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    weights: Annotated[
        Path | None, typer.Option("--weights", help="Retargeting weights (default: the shipped ones).")
    ] = None,
) -> None:
    """Render a reference, a driver and the ground truth; train; drive with both methods; write the report."""
    import dataclasses
    import time

    from clone.demo import QUICK, DemoConfig, check_out, run_demo
    from clone.outputs import check_number
    from retarget.runtime import configure_threads, resolve_device

    check_number("--minutes", minutes, 0.1, 7 * 24 * 60.0)
    check_out(out)
    if weights is not None and not weights.is_file():
        raise typer.BadParameter(f"{weights}: no such file", param_hint="--weights")
    try:
        torch_device = resolve_device(device)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--device") from None
    if torch_device.type == "cpu":
        configure_threads()
    config = QUICK if quick else DemoConfig()
    if minutes is not None:
        config = dataclasses.replace(config, minutes=minutes)
    start = time.perf_counter()
    result = run_demo(out, config, device=str(torch_device), weights=weights,
                      stage=lambda text: console.print(f"[bold]clone demo[/bold]: {text}"))
    total = time.perf_counter() - start
    stages = ", ".join(f"{k} {v:.0f} s" for k, v in result.seconds.items())
    console.print(f"done in {total:.0f} s ({stages})")
    for method, numbers in result.summary.items():
        shown = ", ".join(f"{k} {v:.3g}" for k, v in numbers.items() if k in ("ssim", "psnr", "pose_rmse_pct"))
        if shown:
            console.print(f"  {method}: {shown}")
    typer.echo(f"report: {result.report}")
    typer.echo(f"videos: {result.report.parent / 'side_by_side.mp4'}, reference model: {result.model}")
