"""`make bench` = `python -m bench.run`: time every stage against a baseline measured in the same run.

    python -m bench.run                      # default stages (~10 min on 2 shared cores)
    python -m bench.run --only draw,startup  # some stages; other stages already in results.json are kept
    python -m bench.run --quick              # smaller tracks, fewer repeats
    python -m bench.run --only train_quality # opt-in: SSIM after 1, 3, 10 minutes of training
    python -m bench.run --only real --minutes 1,10 --strips /tmp/strips  # opt-in: real people, these budgets
    python -m bench.run --only real --minutes 3 --starts prior            # only the default start

Writes ``results.json`` and ``results.md`` into ``--out`` (default: this folder). Each row carries the
1/5/15-minute load average when it was measured: the machine is shared, so absolute figures move with
the load while the ratios to the same-run baselines move less.
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import time
import traceback
from pathlib import Path
from typing import Any

from bench.harness import load_average, machine_info

log = logging.getLogger("bench")

# name -> (module, in the default run)
STAGES: dict[str, tuple[str, bool]] = {
    "retarget": ("bench.retargeting", True),
    "startup": ("bench.startup", True),
    "draw": ("bench.draw", True),
    "generator": ("bench.generator", True),
    "train_quality": ("bench.train_quality", False),
    "real": ("bench.real", False),
    "extract": ("bench.extract", True),
    "drive": ("bench.drive", True),
    "gpu": ("bench.gpu", True),
    "search": ("bench.search", True),
    "io": ("bench.io", True),
}
SCHEMA_VERSION = 1
HERE = Path(__file__).resolve().parent


def select(only: str | None) -> list[str]:
    """Stage names to run: the ``--only`` list in registry order, else the default ones."""
    if not only:
        return [name for name, (_, default) in STAGES.items() if default]
    names = [n.strip() for n in only.split(",") if n.strip()]
    unknown = [n for n in names if n not in STAGES]
    if unknown:
        raise ValueError(f"unknown stage(s) {', '.join(unknown)}; valid: {', '.join(STAGES)}")
    return [n for n in STAGES if n in names]


def cpu_info() -> dict[str, object]:
    """CPU model and the vector extensions that decide bf16 / int8 speed."""
    model, flags = "", set()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name") and not model:
                model = line.split(":", 1)[1].strip()
            elif line.startswith("flags") and not flags:
                flags = set(line.split(":", 1)[1].split())
    except OSError:
        pass
    wanted = ("avx2", "fma", "avx512f", "avx512_bf16", "avx512_vnni", "amx_bf16")
    return {"cpu_model": model, "cpu_flags": [f for f in wanted if f in flags]}


def run_stage(name: str, quick: bool, repeats: int | None, **options: object) -> dict[str, Any]:
    """Run one stage (``options``: the stage-specific ones given, e.g. ``minutes``); a failure is recorded in the
    result rather than stopping the others."""
    module = importlib.import_module(STAGES[name][0])
    before = load_average()
    t0 = time.perf_counter()
    try:
        result = module.run(quick=quick, repeats=repeats, **{k: v for k, v in options.items() if v is not None})
    except Exception as exc:  # noqa: BLE001 - report and go on with the other stages
        log.error("stage %s failed: %s", name, exc)
        result = {"rows": [], "notes": [], "error": "".join(traceback.format_exception_only(exc)).strip(),
                  "traceback": traceback.format_exc()[-3000:]}
    result.update({
        "seconds": round(time.perf_counter() - t0, 1),
        "load_average_before": before,
        "load_average_after": load_average(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
        "quick": quick,
    })
    return result


def _fmt(v: object) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1000 else f"{v:,.0f}"
    return str(v)


def to_markdown(doc: dict[str, Any]) -> str:
    m = doc["machine"]
    lines = [
        "# clone2d benchmarks", "",
        "| machine | CPU | cores | torch | threads (default) | date | load avg (1/5/15 min) at start |",
        "|---|---|---|---|---|---|---|",
        (f"| {m['machine']} | {m.get('cpu_model', '')} ({', '.join(m.get('cpu_flags', []))}) | "
        f"{m['cpus_available']} | {m['torch']} | {m['torch_threads']} | {m['date']} | "
        f"{' / '.join(map(str, doc['load_average']))} |"), "",
        ("Each figure: median of repeated runs after warm-up; speedup > 1 means better than the baseline of the "
        "same row, measured in the same run. Load average is the machine's at the time of the row."), "",
    ]
    for name, st in doc["stages"].items():
        lines += [f"## {name}", "",
                  f"{st.get('date', '')}, {st.get('seconds', '?')} s, load avg "
                  f"{' / '.join(map(str, st.get('load_average_before', [])))} -> "
                  f"{' / '.join(map(str, st.get('load_average_after', [])))}"
                  + (" (--quick)" if st.get("quick") else ""), ""]
        if st.get("error"):
            lines += [f"**failed**: `{st['error']}`", ""]
        if st.get("rows"):
            lines += ["| case | variant | value | unit | baseline | speedup | load avg 1 min | details |",
                      "|---|---|---|---|---|---|---|---|"]
            for r in st["rows"]:
                extra = ", ".join(f"{k}={_fmt(v)}" for k, v in r.get("extra", {}).items() if v is not None)
                base = f"{_fmt(r['baseline'])} ({r['baseline_variant']})" if r.get("baseline") is not None else ""
                la = r.get("load_average") or [""]
                lines.append(f"| {r['case']} | {r['variant']} | {_fmt(r['value'])} | {r['unit']} | {base} | "
                             f"{_fmt(r['speedup'])} | {la[0]} | {extra} |")
            lines.append("")
        lines += [f"- {n}" for n in st.get("notes", [])] + [""]
    return "\n".join(lines)


def write_results(out: Path, new_stages: dict[str, Any], machine: dict[str, Any], load_start: list[float]) -> Path:
    """Merge ``new_stages`` into ``out/results.json`` (other stages kept) and rewrite results.md."""
    from pose_io.atomic import atomic_file

    out.mkdir(parents=True, exist_ok=True)
    path = out / "results.json"
    stages: dict[str, Any] = {}
    if path.is_file():
        try:
            old = json.loads(path.read_text())
            if old.get("schema_version") == SCHEMA_VERSION:
                stages = old.get("stages", {})
        except (OSError, ValueError):
            log.warning("%s unreadable; starting afresh", path)
    stages.update(new_stages)
    ordered = {n: stages[n] for n in STAGES if n in stages}
    doc = {"schema_version": SCHEMA_VERSION, "machine": machine, "load_average": load_start, "stages": ordered}
    with atomic_file(path, overwrite=True) as tmp:
        Path(tmp).write_text(json.dumps(doc, indent=1) + "\n")
    with atomic_file(out / "results.md", overwrite=True) as tmp:
        Path(tmp).write_text(to_markdown(doc))
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.run", description=__doc__.splitlines()[0])
    parser.add_argument("--only", help=f"comma-separated stages: {', '.join(STAGES)}")
    parser.add_argument("--quick", action="store_true", help="smaller tracks, fewer repeats")
    parser.add_argument("--out", type=Path, default=HERE, help="folder for results.json / results.md")
    parser.add_argument("--repeats", type=int, default=None, help="override repeats where a stage supports it")
    parser.add_argument("--minutes", help="training budgets of the `real` stage, e.g. 1,3,10 (default 3)")
    parser.add_argument("--starts", help="`real` stage: comma-separated starts, prior and/or none (default both)")
    parser.add_argument("--strips", type=Path, default=None,
                        help="`real` stage: write real | generated strips of held-out frames into this folder")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    try:
        names = select(args.only)
    except ValueError as exc:
        parser.error(str(exc))
    import torch

    torch.set_num_threads(1)  # shared machine; stages that measure 2 threads set it themselves
    machine = {**machine_info(), **cpu_info()}
    load_start = load_average()
    done: dict[str, Any] = {}
    for name in names:
        log.info("stage %s (load average %s)", name, load_average())
        done[name] = run_stage(name, args.quick, args.repeats, minutes=args.minutes, strips=args.strips,
                               starts=args.starts)
        path = write_results(args.out, {name: done[name]}, machine, load_start)  # partial results survive
        log.info("stage %s: %s s%s", name, done[name]["seconds"], " FAILED" if done[name].get("error") else "")
    print((args.out / "results.md").read_text())
    log.info("wrote %s and results.md", path)
    return 1 if any(st.get("error") for st in done.values()) else 0


if __name__ == "__main__":
    raise SystemExit(main())
