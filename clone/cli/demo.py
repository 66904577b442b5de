"""`clone demo`: the whole pipeline on the built-in synthetic pairs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from clone.cli.common import DEVICE_HELP, MAX_THREADS, console, user_errors


@user_errors
def demo_command(
    out: Annotated[Path, typer.Option("--out", help="Output folder (a folder an earlier demo made is replaced).")] = Path(
        "demo_out"
    ),
    quick: Annotated[bool, typer.Option("--quick", help="Shorter clips, a 128² model and a 1-minute training budget.")] = False,
    minutes: Annotated[
        float | None, typer.Option("--minutes", min=0.1, help="Training budget of the reference model in minutes (default 5.5; 1 with --quick).")
    ] = None,
    device: Annotated[str, typer.Option("--device", help=DEVICE_HELP)] = "auto",
    weights: Annotated[
        Path | None, typer.Option("--weights", help="Retargeting weights (default: the shipped ones).")
    ] = None,
    threads: Annotated[
        int | None, typer.Option("--threads", min=1, help="CPU threads (default: the cores other processes leave "
                                 "free now; training steps in the budget scale with them).")
    ] = None,
) -> None:
    """Render a reference and three driver pairs with ground truth; train once; report every pair and sum up."""
    import dataclasses
    import time

    from clone.demo import QUICK, DemoConfig, check_out, run_demo
    from pose_io.outputs import check_number
    from retarget.runtime import configure_threads, resolve_device

    check_number("--minutes", minutes, 0.1, 7 * 24 * 60.0)
    check_number("--threads", threads, 1, MAX_THREADS)
    check_out(out)
    if weights is not None and not weights.is_file():
        raise typer.BadParameter(f"{weights}: no such file", param_hint="--weights")
    try:
        torch_device = resolve_device(device)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--device") from None
    if torch_device.type == "cpu":
        configure_threads(threads)
    config = QUICK if quick else DemoConfig()
    if minutes is not None:
        config = dataclasses.replace(config, minutes=minutes)
    start = time.perf_counter()
    result = run_demo(out, config, device=str(torch_device), weights=weights,
                      stage=lambda text: console.print(f"[bold]clone demo[/bold]: {text}"),
                      grow_threads=threads is None)
    total = time.perf_counter() - start
    stages = ", ".join(f"{k} {v:.0f} s" for k, v in result.seconds.items())
    console.print(f"done in {total:.0f} s ({stages}; {result.steps} training steps)")
    for pair, methods in result.summary.items():
        console.print(f"  {pair}: " + _headline(methods))
    typer.echo(f"report: {result.report}")
    typer.echo(f"pairs: {', '.join(str(result.out / p / 'report') for p in result.summary)}; "
               f"reference model: {result.model}")


def _headline(methods: dict[str, dict[str, float]]) -> str:
    """A pair's key numbers, global scaling / retargeted: the primary pose error and ratio, person SSIM, view."""
    gs, rt = methods.get("global-scale", {}), methods.get("retarget", {})

    def both(key: str, fmt: str) -> str:
        values = (gs.get(key), rt.get(key))
        return " / ".join("–" if v is None else fmt.format(v) for v in values)

    error = (gs.get("pose_rmse_pct"), rt.get("pose_rmse_pct"))
    ratio = f" ({error[0] / error[1]:.2f}x)" if None not in error and error[1] > 0 else ""
    return (f"pose error {both('pose_rmse_pct', '{:.2f}')} % of height{ratio}, person SSIM "
            f"{both('ssim_crop', '{:.3f}')}, faces the true side {both('facing_share', '{:.2f}')} "
            "(global scaling / retargeted)")
