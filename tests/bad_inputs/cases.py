"""The bad-input corpus: every case is an argv, the files it starts with, and the expectation (one error line).

``{t}`` in an argument stands for the case's ``tmp_path``. Cases are built from small tables: for every command
a base argv that is good except for what the case changes, then its bad option values, bad input files, and bad
output paths. A case whose fix belongs to pose_io (being hardened separately) carries ``xfail``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from tests.bad_inputs import builders as b

POSE_IO = "pose_io hardening in progress"


@dataclass(frozen=True)
class Case:
    id: str
    argv: tuple[str, ...]
    build: tuple[b.Builder, ...] = ()
    xfail: str | None = None
    subprocess: bool = False  # run `python -m clone` instead of in-process (none yet needs it)


CASES: list[Case] = []


def add(id_: str, argv: Sequence[str], build: Iterable[b.Builder] = (), xfail: str | None = None) -> None:
    assert all(c.id != id_ for c in CASES), id_
    CASES.append(Case(id_, tuple(argv), tuple(build), xfail))


def options(name: str, base: Sequence[str], build: Sequence[b.Builder], table: dict[str, Sequence[str]],
            xfail: dict[tuple[str, str], str] | None = None) -> None:
    """One case per (option, bad value), the option appended to ``base``."""
    for option, values in table.items():
        for value in values:
            add(f"{name} {option}={value}", [*base, option, value], build, (xfail or {}).get((option, value)))


def paths(name: str, base: Sequence[str], build: Sequence[b.Builder], option: str, values: Sequence[str],
          xfail: dict[str, str] | None = None) -> None:
    """One case per bad path given to ``option`` (appended; positional when ``option`` is empty)."""
    for value in values:
        argv = [*base, option, value] if option else [*base, value]
        add(f"{name} {option or 'ARG'}={value.replace('{t}/', '')}", argv, build, (xfail or {}).get(value))


NEG_FLOATS = ["0", "-1", "nan", "inf", "-inf", "1e300"]
NONFINITE = ["nan", "inf", "-inf"]
BAD_COUNTS = ["0", "-1", "nan", "99999999999"]
EVERY_OUTPUT = [b.old_outputs, b.a_folder, b.file_parent]
BAD_POSE_INPUTS = {  # path -> builder, xfail reason (None: must pass now)
    "{t}/missing.npz": (None, None),
    "{t}/badjson": (b.bad_json_dir, None),
    "{t}/wrongjson": (b.wrong_json_dir, None),
    "{t}/empty": (b.empty_dir, None),
    "{t}/bad.npz": (b.bad_npz, None),
    "{t}/wrong.npz": (b.wrong_npz, None),
    "{t}/bad.csv": (b.bad_csv, None),
    "{t}/empty.csv": (b.empty_csv, None),
    "{t}/huge.npz": (b.huge_npz, None),
    "{t}/empty.bin": (b.empty_file, None),
    "{t}/notes.txt": (b.text_file, None),
}
BAD_MODELS = {
    "{t}/missing.pt": None,
    "{t}/garbage.pt": b.garbage_pt,
    "{t}/foreign.pt": b.foreign_pt,
    "{t}/retarget.pt": b.retarget_pt,
    "{t}/notes.txt": b.text_file,
    "{t}/empty": b.empty_dir,
}


def pose_inputs(name: str, before: Sequence[str], after: Sequence[str], build: Sequence[b.Builder] = ()) -> None:
    for path, (builder, xfail) in BAD_POSE_INPUTS.items():
        extra = [builder] if builder else []
        add(f"{name} input={path.replace('{t}/', '')}", [*before, path, *after], [*build, *extra], xfail)


def models(name: str, base: Sequence[str], build: Sequence[b.Builder], option: str) -> None:
    for path, builder in BAD_MODELS.items():
        if option == "--weights" and path.endswith("retarget.pt"):
            continue  # retargeting weights ARE what --weights takes
        add(f"{name} {option}={path.replace('{t}/', '')}", [*base, option, path],
            [*build, *([builder] if builder else [])])


# ------------------------------------------------------------------------------------------------ pose

options("pose info", ["pose", "info", "{t}/poses.npz"], [b.poses_npz], {
    "--in-fps": NEG_FLOATS, "--person": ["-1", "nan", "x"], "--format": ["bogus", ""],
    "--size": ["0x0", "-5x5", "axb", "100000000x100000000", "nanxnan", "640"],
})
pose_inputs("pose info", ["pose", "info"], [])
add("pose info no args at all", ["pose", "info", "--bogus"])

SHOW = ["pose", "show", "{t}/poses.npz", "--out", "{t}/new.mp4"]
options("pose show", SHOW, [b.poses_npz], {"--in-fps": NEG_FLOATS, "--person": ["-1"], "--size": ["0x0", "1x"]})
paths("pose show", ["pose", "show", "{t}/poses.npz"], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/preview.txt", "{t}/result", "{t}/old.mp4", "{t}/folder.mp4", "{t}/blocker/x.mp4", "/proc/x.mp4",
       "{t}/dir"], )
add("pose show existing mp4", [*SHOW[:3], "--out", "{t}/old.mp4"], [b.poses_npz, b.old_mp4])
paths("pose show", SHOW, [b.poses_npz, b.empty_dir, b.text_file], "--frames",
      ["{t}/missing_frames", "{t}/empty", "{t}/notes.txt"])
pose_inputs("pose show", ["pose", "show"], ["--out", "{t}/new.mp4"])

CONVERT = ["pose", "convert", "{t}/poses.npz", "{t}/new.npz"]
options("pose convert", CONVERT, [b.poses_npz], {
    "--fill-gaps": ["-1", "nan", "99999999999"], "--smooth": ["-1", "nan", "inf", "1e300"],
    "--fps": NEG_FLOATS, "--in-fps": ["0", "nan"], "--to": ["bogus"], "--to-layout": ["bogus"],
})
paths("pose convert", ["pose", "convert", "{t}/poses.npz"], [b.poses_npz, *EVERY_OUTPUT], "",
      ["{t}/out.txt", "{t}/old.npz", "{t}/old.csv", "{t}/olddir", "{t}/blocker/x.npz", "/proc/x.npz",
       "{t}/folder.mp4"])
add("pose convert --to csv into .npz", [*CONVERT, "--to", "csv"], [b.poses_npz])
add("pose convert --to openpose into .npz", [*CONVERT, "--to", "openpose"], [b.poses_npz])
pose_inputs("pose convert", ["pose", "convert"], ["{t}/new.npz"])

EXTRACT = ["pose", "extract", "{t}/notes.txt", "--out", "{t}/extracted"]
options("pose extract", EXTRACT, [b.text_file], {"--min-visibility": ["-0.1", "1.5", "nan", "inf"]})
paths("pose extract", ["pose", "extract", "{t}/notes.txt"], [b.text_file, *EVERY_OUTPUT], "--out",
      ["{t}/olddir", "{t}/old.npz", "{t}/blocker/x", "/proc/x"])
add("pose extract missing video", ["pose", "extract", "{t}/missing.mp4", "--out", "{t}/extracted"])

# ------------------------------------------------------------------------------------------------ retarget

APPLY = ["retarget", "apply", "{t}/poses.npz", "--skeleton", "{t}/poses.npz", "--out", "{t}/new.npz",
         "--device", "cpu"]
paths("retarget apply", APPLY, [b.poses_npz, *EVERY_OUTPUT], "--preview",
      ["{t}/x.gif", "{t}/x", "{t}/old.mp4", "{t}/folder.mp4", "{t}/blocker/x.mp4", "{t}/new.npz"])
paths("retarget apply", APPLY[:5], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/o.txt", "{t}/old.npz", "{t}/olddir", "{t}/blocker/o.npz", "/proc/o.npz"])
options("retarget apply", APPLY, [b.poses_npz], {"--size": ["0x0", "axb"], "--device": ["bogus", "cuda:x"]})
models("retarget apply", APPLY, [b.poses_npz], "--weights")
pose_inputs("retarget apply", ["retarget", "apply"], APPLY[3:], [b.poses_npz])
paths("retarget apply", APPLY, [b.poses_npz, b.bad_npz], "--view", ["{t}/missing.npz", "{t}/bad.npz"])
options("retarget apply", APPLY, [b.poses_npz], {"--backend": ["bogus", ""], "--to": ["csv", "bogus"],
                                                 "--threads": ["0", "nan"]})
add("retarget apply --backend numpy on cuda", [*APPLY, "--backend", "numpy", "--device", "cuda"], [b.poses_npz])
# Several inputs (a folder of clips, or more than one path): every input is checked before any output is written.
BATCH = ["retarget", "apply", "{t}/clips", "--skeleton", "{t}/poses.npz", "--out", "{t}/moved", "--device", "cpu"]
add("retarget apply batch with a corrupt clip", BATCH, [b.poses_npz, b.clips_bad])
add("retarget apply batch with a missing input", ["retarget", "apply", "{t}/clips/a.npz", "{t}/missing.npz",
                                                  *BATCH[3:]], [b.poses_npz, b.clips])
add("retarget apply batch input named twice", ["retarget", "apply", "{t}/clips", "{t}/clips/a.npz", *BATCH[3:]],
    [b.poses_npz, b.clips])
add("retarget apply batch outputs clash", BATCH, [b.poses_npz, b.clips_clash])
add("retarget apply batch output exists", BATCH, [b.poses_npz, b.clips, b.old_batch_output])
add("retarget apply batch --preview", [*BATCH, "--preview", "{t}/p.mp4"], [b.poses_npz, b.clips])
paths("retarget apply batch", BATCH[:5], [b.poses_npz, b.clips, *EVERY_OUTPUT], "--out",
      ["{t}/old.npz", "{t}/o.npz", "{t}/blocker/o", "/proc/o"])

TRAIN = ["retarget", "train", "--mocap", "{t}/mocap", "--out", "{t}/new.pt", "--device", "cpu"]
options("retarget train", TRAIN, [b.mocap_empty], {
    "--minutes": NEG_FLOATS, "--epochs": BAD_COUNTS, "--lr": ["0", "nan", "inf", "2"],
    "--trajectory-weight": ["-1", "nan", "inf"], "--foot-weight": ["-1", "nan"], "--triplet-weight": ["nan"],
    "--triplet-margin": ["-1", "inf"], "--spread-weight": ["nan"], "--cycle-weight": ["-1", "nan"],
    "--extra-characters": ["-1", "99999"], "--extra-spread": ["0", "nan", "9"], "--batch-size": ["0", "999999999"],
    "--max-pitch": ["-1", "nan", "61"], "--perspective": ["-0.1", "nan", "1.5"],
    "--frontal-share": ["-0.1", "nan", "1.5"], "--skeleton-proportion-weight": ["-1", "nan"],
    "--workers": ["-1", "999999"], "--threads": ["0", "9999999"], "--variant": ["bogus"], "--ablation": ["x"],
})
paths("retarget train", TRAIN[:4], [b.mocap_empty, *EVERY_OUTPUT], "--out",
      ["{t}/old.pt", "{t}/olddir", "{t}/blocker/o.pt", "/proc/o.pt"])
add("retarget train empty mocap", TRAIN, [b.mocap_empty])
add("retarget train missing mocap", ["retarget", "train", "--mocap", "{t}/nomocap", "--out", "{t}/n.pt"])
for path, builder in BAD_MODELS.items():
    if builder is not None and path.endswith(".pt"):
        add(f"retarget train --resume {path[4:]}", ["retarget", "train", "--mocap", "{t}/mocap", "--out", path,
                                                      "--resume", "--device", "cpu"], [b.mocap_empty, builder])
        if not path.endswith("retarget.pt"):
            add(f"retarget train --init {path[4:]}", [*TRAIN, "--init", path], [b.mocap_empty, builder])

EVAL = ["retarget", "eval", "--mocap", "{t}/mocap", "--out", "{t}/evalout", "--device", "cpu"]
options("retarget eval", EVAL, [b.mocap_empty], {
    "--pairs": BAD_COUNTS, "--length": ["15", "nan", "999999999"], "--threads": ["0"], "--split": ["bogus"],
    "--noise": ["-0.1", "nan", "0.5"], "--max-yaw": ["-1", "nan", "91"], "--max-pitch": ["-1", "nan", "61"],
    "--reference-length": ["0", "9999999"], "--code-grids": ["0", "nan", "1001"],
    "--probe-steps": ["-1", "nan", "1000001"],
})
paths("retarget eval", EVAL[:4], [b.mocap_empty, *EVERY_OUTPUT], "--out", ["{t}/olddir", "{t}/old.npz",
                                                                          "{t}/blocker/e"])
add("retarget eval missing mocap", ["retarget", "eval", "--mocap", "{t}/nomocap", "--out", "{t}/e"])

EVALC = ["retarget", "eval-cloning", "--mocap", "{t}/mocap", "--out", "{t}/clout", "--device", "cpu"]
options("retarget eval-cloning", EVALC, [b.mocap_empty], {
    "--clips": ["0", "-1", "nan", "999999999"], "--frames": ["15", "nan", "999999999"], "--threads": ["0"],
    "--split": ["bogus"], "--compare": ["noequals", "=x"],
})
paths("retarget eval-cloning", EVALC[:4], [b.mocap_empty, *EVERY_OUTPUT], "--out", ["{t}/olddir", "{t}/old.npz",
                                                                                   "{t}/blocker/e"])
add("retarget eval --compare twice", [*EVAL, "--compare", "a=x.pt", "--compare", "a=y.pt"], [b.mocap_empty])
add("retarget eval-cloning --compare twice", [*EVALC, "--compare", "a=x.pt", "--compare", "a=y.pt"], [b.mocap_empty])
add("retarget eval-cloning missing mocap", ["retarget", "eval-cloning", "--mocap", "{t}/nomocap", "--out", "{t}/e"])

INTERP = ["retarget", "interpolate", "{t}/poses.npz", "{t}/poses.npz", "--out", "{t}/grid.npz", "--device", "cpu"]
options("retarget interpolate", INTERP, [b.poses_npz], {
    "--steps": ["1", "17", "nan"], "--frames": ["7", "-1", "999999999999"], "--cell": ["31", "513"],
    "--vary": ["motion", "motion,motion", "a,b"], "--canvas": ["bogus"], "--size": ["0x0"],
})
paths("retarget interpolate", INTERP[:4], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/g.gif", "{t}/old.npz", "{t}/folder.mp4", "{t}/blocker/g.mp4", "{t}/grid"])
models("retarget interpolate", INTERP, [b.poses_npz], "--weights")

# ------------------------------------------------------------------------------------------------ train-ref

REF = ["train-ref", "{t}/ref/poses", "{t}/ref/frames", "--out", "{t}/new.pt", "--device", "cpu", "--threads", "1"]
options("train-ref", REF, [b.reference], {
    "--size": ["16", "48", "65536", "0", "-32", "2048", "nan"], "--steps": ["0", "-1", "99999999999"],
    "--minutes": NEG_FLOATS, "--batch-size": ["0", "999999"], "--threads": ["0"], "--canvas": ["bogus"],
    "--align": ["bogus"], "--device": ["bogus"],
})
paths("train-ref", REF[:3], [b.reference, *EVERY_OUTPUT], "--out",
      ["{t}/old.pt", "{t}/olddir", "{t}/blocker/m.pt", "/proc/m.pt", "{t}/old"])
add("train-ref existing preview", [*REF[:3], "--out", "{t}/old.pt", "--steps", "1"], [b.reference, b.old_outputs])
add("train-ref --resume --overwrite", [*REF, "--resume", "--overwrite"], [b.reference])
add("train-ref --resume nothing", [*REF, "--resume"], [b.reference])
for path, builder in BAD_MODELS.items():
    if builder is not None and path.endswith(".pt"):
        add(f"train-ref --resume {path[4:]}", [*REF[:3], "--out", path, "--resume", "--device", "cpu"],
            [b.reference, builder])
        add(f"train-ref --resume --size 32 {path[4:]}", [*REF[:3], "--out", path, "--resume", "--size", "32"],
            [b.reference, builder])
add("train-ref missing frames", ["train-ref", "{t}/poses.npz", "{t}/noframes", "--out", "{t}/m.pt"], [b.poses_npz])
add("train-ref frames are a text file", ["train-ref", "{t}/poses.npz", "{t}/notes.txt", "--out", "{t}/m.pt"],
    [b.poses_npz, b.text_file])
pose_inputs("train-ref", ["train-ref"], ["{t}/ref/frames", "--out", "{t}/m.pt", "--device", "cpu"], [b.reference])

# ------------------------------------------------------------------------------------------------ train-prior

PRIOR = ["train-prior", "--mocap", "{t}/mocap", "--out", "{t}/new.pt", "--device", "cpu", "--threads", "1"]
options("train-prior", PRIOR, [b.mocap_empty], {
    "--size": ["16", "48", "2048", "nan"], "--performers": BAD_COUNTS, "--frames": ["1", "-1", "99999999999"],
    "--seed": ["-1", "nan"], "--steps": ["0", "-1"], "--minutes": NEG_FLOATS, "--threads": ["0"],
    "--device": ["bogus"],
})
paths("train-prior", PRIOR[:3], [b.mocap_empty, *EVERY_OUTPUT], "--out",
      ["{t}/old.pt", "{t}/olddir", "{t}/blocker/m.pt", "/proc/m.pt", "{t}/old"])
paths("train-prior --export", PRIOR, [b.mocap_empty, *EVERY_OUTPUT], "--export",
      ["{t}/new.pt", "{t}/old.pt", "{t}/dir", "{t}/blocker/p.pt", "/proc/p.pt"])
add("train-prior empty mocap", PRIOR, [b.mocap_empty])
add("train-prior missing mocap", ["train-prior", "--mocap", "{t}/nomocap", "--out", "{t}/n.pt"])
add("train-prior too many frames", [*PRIOR, "--performers", "4096", "--frames", "1000"], [b.mocap_empty])
add("train-prior --resume nothing", [*PRIOR, "--resume"], [b.mocap_empty])
add("train-prior --init missing", [*PRIOR, "--init", "{t}/none.pt"], [b.mocap_empty])
add("train-prior --init --resume", [*PRIOR, "--init", "{t}/old.pt", "--resume"], [b.mocap_empty, b.old_outputs])
add("train-prior --resume --overwrite", [*PRIOR, "--resume", "--overwrite"], [b.mocap_empty])
for path, builder in BAD_MODELS.items():
    if builder is not None and path.endswith(".pt"):
        add(f"train-prior --resume {path[4:]}", [*PRIOR[:3], "--out", path, "--resume", "--device", "cpu"],
            [b.mocap_empty, builder])

# ------------------------------------------------------------------------------------------------ drive, report

DRIVE = ["drive", "{t}/poses.npz", "--out", "{t}/new.mp4", "--device", "cpu"]
models("drive", DRIVE, [b.poses_npz], "--model")
add("drive default model missing", DRIVE, [b.poses_npz])
options("drive", [*DRIVE, "--model", "{t}/garbage.pt"], [b.poses_npz, b.garbage_pt], {
    "--max-gap": ["-1", "99999999999"], "--threads": ["0"], "--method": ["bogus"], "--device": ["tpu"],
    "--stage": ["bogus", "RAW", ""], "--runtime": ["bogus", ""], "--refine-steps": ["-1", "nan", "1001"],
})
paths("drive", DRIVE[:2], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/result", "{t}/out.avi", "{t}/old.mp4", "{t}/folder.mp4", "{t}/blocker/o.mp4", "/proc/o.mp4"])
paths("drive", DRIVE, [b.poses_npz, *EVERY_OUTPUT], "--poses-out",
      ["{t}/p.txt", "{t}/old.npz", "{t}/olddir", "{t}/blocker/p.npz", "{t}/new.mp4"])
pose_inputs("drive", ["drive"], DRIVE[2:] + ["--model", "{t}/foreign.pt"], [b.foreign_pt])

REPORT = ["report", "{t}/poses.npz", "--out", "{t}/rep", "--device", "cpu"]
models("report", REPORT, [b.poses_npz], "--model")
paths("report", REPORT[:2], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/olddir", "{t}/old.npz", "{t}/blocker/r"])
paths("report", [*REPORT, "--model", "{t}/foreign.pt"], [b.poses_npz, b.foreign_pt], "--gt-poses",
      ["{t}/missing.npz"])
paths("report", [*REPORT, "--model", "{t}/foreign.pt"], [b.poses_npz, b.foreign_pt], "--gt-frames",
      ["{t}/missing_frames"])
options("report", [*REPORT, "--model", "{t}/foreign.pt"], [b.poses_npz, b.foreign_pt],
        {"--device": ["bogus"], "--stage": ["bogus", ""], "--refine-steps": ["-1", "1001"]})
add("report missing driver", ["report", "{t}/missing.npz", "--out", "{t}/rep", "--model", "{t}/foreign.pt"],
    [b.foreign_pt])

STRIP = ["strip", "{t}/foreign.pt", "--out", "{t}/small.pt"]
for path, builder in BAD_MODELS.items():
    add(f"strip MODEL={path.replace('{t}/', '')}", ["strip", path, "--out", "{t}/small.pt"], [builder] if builder else [])
paths("strip", STRIP[:2], [b.foreign_pt, *EVERY_OUTPUT], "--out",
      ["{t}/small.npz", "{t}/old.pt", "{t}/olddir", "{t}/blocker/s.pt", "{t}/foreign.pt"])
add("strip no --out", ["strip", "{t}/foreign.pt"], [b.foreign_pt])

# ------------------------------------------------------------------------------------------------ demo

DEMO = ["demo", "--out", "{t}/demo", "--device", "cpu"]
for path, builder in BAD_MODELS.items():
    if path.endswith(".pt") and not path.endswith("retarget.pt"):
        add(f"demo over an earlier demo --weights {path[4:]}", [*DEMO, "--weights", path],
            [b.earlier_demo, *([builder] if builder else [])])
options("demo", DEMO, [b.earlier_demo], {"--minutes": ["0", "-1", "nan", "inf", "1e300"], "--device": ["x"],
                                         "--threads": ["0", "99999999"]})
paths("demo", ["demo", "--device", "cpu"], [*EVERY_OUTPUT], "--out",
      ["{t}/olddir", "{t}/old.npz", "{t}/blocker/d", "/proc/d"])

# ------------------------------------------------------------------------------------------------ synth, world

SYNTH = ["synth", "render", "{t}/bad.bvh", "--out", "{t}/synth"]
options("synth render", SYNTH, [b.bad_motion], {
    "--yaw": ["nan", "inf", "-inf", "1e300"], "--pitch": ["nan", "90", "-100"], "--size": ["0", "15", "1000000"],
    "--start": ["-1"], "--frames": ["0", "-1"], "--fps": ["0", "-1", "nan", "inf"],
    "--character": ["nobody"],
})
add("synth render bad motion", SYNTH, [b.bad_motion])
add("synth render missing motion", ["synth", "render", "{t}/missing.bvh", "--out", "{t}/synth"])
add("synth render motion is a folder", ["synth", "render", "{t}/empty", "--out", "{t}/synth"], [b.empty_dir])
paths("synth render", SYNTH[:3], [b.bad_motion, *EVERY_OUTPUT], "--out",
      ["{t}/olddir", "{t}/old.npz", "{t}/blocker/s", "/proc/s"])

WORLD = ["world", "build", "--mocap", "{t}/mocap", "--cache", "{t}/cache"]
options("world build", WORLD, [b.mocap_empty], {
    "--fps": ["0", "-1", "nan", "inf"], "--train-characters": ["0", "999999999"],
    "--val-characters": ["0", "999999999"], "--test-characters": ["-1", "999999999"],
    "--window": ["1", "999999999"], "--stride": ["0", "999999999"],
})
add("world build empty mocap", WORLD, [b.mocap_empty])
add("world build missing mocap", ["world", "build", "--mocap", "{t}/nomocap", "--cache", "{t}/cache"])
paths("world build", WORLD[:4], [b.mocap_empty, *EVERY_OUTPUT], "--cache",
      ["{t}/old.npz", "{t}/blocker/c", "/proc/c"])
for verb in ("list", "clean"):
    paths(f"world {verb}", ["world", verb], [*EVERY_OUTPUT], "--cache", ["{t}/nowhere", "{t}/old.npz"])
options("world clean", ["world", "clean", "--cache", "{t}/olddir"], [*EVERY_OUTPUT],
        {"--keep": ["-1", "nan", "99999999999"]})

# ------------------------------------------------------------------------------------------------ search

INDEX = ["search", "index", "{t}/poses.npz", "--out", "{t}/idx.npz", "--device", "cpu"]
paths("search index", INDEX[:3], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/old.npz", "{t}/olddir", "{t}/blocker/i.npz", "/proc/i.npz"])
options("search index", INDEX, [b.poses_npz], {"--threads": ["0", "99999999"], "--size": ["0x0"]})
models("search index", INDEX, [b.poses_npz], "--weights")
add("search index missing track", ["search", "index", "{t}/missing.npz", "--out", "{t}/idx.npz"])
add("search index only bad tracks", ["search", "index", "{t}/bad.npz", "--out", "{t}/idx.npz", "--device", "cpu"],
    [b.bad_npz])

QUERY = ["search", "query", "{t}/poses.npz", "--device", "cpu"]
paths("search query", QUERY, [b.poses_npz, b.bad_npz, b.wrong_npz, b.text_file, b.empty_dir], "--index",
      ["{t}/missing.npz", "{t}/bad.npz", "{t}/wrong.npz", "{t}/poses.npz", "{t}/notes.txt", "{t}/empty"])
options("search query", [*QUERY, "--index", "{t}/bad.npz"], [b.poses_npz, b.bad_npz], {
    "--top": ["0", "nan", "999999999999"], "--per-track": ["0", "-1"], "--threads": ["0"],
})

SEVAL = ["search", "eval", "--mocap", "{t}/mocap", "--device", "cpu"]
options("search eval", SEVAL, [b.mocap_empty], {"--queries": BAD_COUNTS, "--length": ["15", "999999999"]})
paths("search eval", SEVAL, [b.mocap_empty, *EVERY_OUTPUT], "--out",
      ["{t}/r.txt", "{t}/old.json", "{t}/olddir", "{t}/blocker/r.json"])
add("search eval missing mocap", ["search", "eval", "--mocap", "{t}/nomocap"])

# ------------------------------------------------------------------------------------------------ cartoon

CARTOON = ["cartoon", "{t}/poses.npz", "--character", "standard", "--out", "{t}/c.mp4", "--device", "cpu"]
options("cartoon", CARTOON, [b.poses_npz], {"--yaw": ["nan", "inf", "91", "-91"], "--size": ["0x0"],
                                            "--refine-steps": ["-1", "1001"]})
paths("cartoon", CARTOON[:4], [b.poses_npz, *EVERY_OUTPUT], "--out",
      ["{t}/c.avi", "{t}/c", "{t}/old.mp4", "{t}/folder.mp4", "{t}/blocker/c.mp4", "/proc/c.mp4"])
paths("cartoon", CARTOON, [b.poses_npz, *EVERY_OUTPUT], "--report",
      ["{t}/r.txt", "{t}/old.json", "{t}/olddir", "{t}/c.mp4"])
paths("cartoon", CARTOON, [b.poses_npz, *EVERY_OUTPUT], "--poses", ["{t}/p.txt", "{t}/old.npz", "{t}/c.mp4"])
for value, builder in (("nobody", None), ("{t}/character.json", b.bad_character), ("{t}/missing.json", None),
                       ("{t}/notes.txt", b.text_file)):
    argv = [*CARTOON[:2], "--character", value, *CARTOON[4:]]
    add(f"cartoon --character={value.replace('{t}/', '')}", argv, [b.poses_npz, *([builder] if builder else [])])
models("cartoon", CARTOON, [b.poses_npz], "--weights")
pose_inputs("cartoon", ["cartoon"], CARTOON[2:])
