"""eval.md: the error tables, the real-track table, the silhouettes and the notes that explain them."""

from __future__ import annotations

from collections.abc import Mapping

from retarget.evaluate.config import PROBE_ROW
from retarget.evaluate.real import markdown_rows


def markdown_report(doc: Mapping) -> str:
    """eval.md: one table per source of cases (method rows, metric columns), the silhouettes, the notes.

    Args:
        doc: the document of eval.json (``config``, ``results``, ``real_pairs``, ``silhouettes``, ``notes``).
    """
    cfg = doc["config"]
    lines = ["# Retargeting evaluation", ""]
    head = ("| method | pose MSE ×10³ | pose RMSE % | pose PCK@.05 | pose PCK@.1 | range of motion | "
            "with root MSE ×10³ | with root PCK@.1 | placed MSE ×10³ | placed PCK@.1 |")  # fmt: skip
    for source, rows in doc["results"].items():
        lines += [f"## {source}: {cfg['pairs']} cases of {cfg['length']} frames", "", head, "|---" * 10 + "|"]
        for name, r in rows.items():
            p, w, pl = r["pose"], r["with_root"], r["placed"]
            lines.append(
                f"| {name} | {p['mse_x1e3']:.2f} ± {p['mse_x1e3_se']:.2f} | {p['rmse_pct']:.1f} | "
                f"{p['pck_0.05']:.3f} | {p['pck_0.1']:.3f} | {p['amplitude']:.2f} | "
                f"{w['mse_x1e3']:.2f} ± {w['mse_x1e3_se']:.2f} | "
                f"{w['pck_0.1']:.3f} | {pl['mse_x1e3']:.2f} | {pl['pck_0.1']:.3f} |"
            )
        lines.append("")
    if doc.get("real_pairs"):
        lines += ["## Real tracks (no ground truth)", "", *markdown_rows(doc["real_pairs"]), ""]
    if doc["silhouettes"]:
        lines += ["## Mean silhouette coefficients of the codes", "",
                  "| network | motion codes (by motion) | skeleton codes (by character) | view codes (by view) |",
                  "|---|---|---|---|"]  # fmt: skip
        errors = doc.get("silhouette_errors", {})
        for name, s in doc["silhouettes"].items():
            se = errors.get(name, {})
            cells = [(f"{s[k]:.3f} ± {se[k]:.3f}" if k in se else f"{s[k]:.3f}") if k in s else "–"
                     for k in ("motion", "body", "view")]  # fmt: skip
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["## Notes", ""] + [f"- {n}" for n in doc["notes"]]
    return "\n".join(lines) + "\n"


def _views(cfg: Mapping) -> str:
    """Which view bins the cases' cameras take (configs written before ``max_yaw`` took all 13)."""
    max_yaw = cfg.get("max_yaw", 90.0)
    return "13 view bins" if max_yaw >= 90 else f"the view bins within ±{max_yaw:g}° of the front"


def report_notes(doc: Mapping) -> list[str]:
    """The notes of eval.md: the protocol, the units, every row's description and the run's remarks.

    Args:
        doc: the document of eval.json so far (``config``, ``methods``, ``silhouettes``, ``remarks``).
    """
    cfg = doc["config"]
    notes = [
        (f"Cases: {cfg['pairs']} per source, seed {cfg['seed']}: the motion of a window performed by character A "
         f"seen by camera A, moved onto character B (≠ A) seen by camera B ({_views(cfg)}, pitch uniform in "
         f"±{cfg['max_pitch']:g}°). Truth: the same 3D motion replayed on B's skeleton (bone directions kept, root "
         "path scaled by the leg ratio, feet on the ground) and projected by camera B."
         + (f" Detector noise: every joint of the driver and reference the methods see moved by Gaussian noise of "
            f"std {cfg['noise']:g} of that person's height (the truth and the 3D references stay clean)."
            if cfg.get("noise", 0) > 0 else "")),
        (f"Reference: a {cfg['reference_length']}-frame window of another motion performed by B and seen by camera "
         "B. Networks take B's skeleton and view codes and the placement from it, the 2D baselines their scale "
         "statistics. The 3D references see the true 3D motion and camera instead."),
        ("Units: coordinates are divided by h, B's height in pixels (skeleton height × pixels per metre). MSE: "
         "mean over frames, joints and x/y of the squared difference, ×10³ (units h² × 10⁻³), ± its standard "
         "error over cases. RMSE: root mean squared joint distance of a case in % of h, averaged over cases. "
         "PCK@a: share of joints within a·h."),
        ("pose: each frame's MidHip subtracted from prediction and truth, the 14 other joints scored (the "
         "paper's numbers are about the pose). with root: all 15 joints, after removing the one translation per "
         "case that best aligns prediction and truth (the root trajectory counts, where in the frame the "
         "reference stood does not). placed: the output as it lands in the reference's frame."),
        ("Range of motion: the summed RMS distance of the joints from their mean positions (MidHip removed), "
         "in units of the body's height, of the output over the truth's (1 = neither damped nor exaggerated). "
         "On real tracks it is the output's over the driver's."),
    ]
    for name, method in doc["methods"].items():
        what = method["description"]
        if method.get("weights"):
            what += f"; weights {method['weights']}"
        if method.get("refine_steps") is not None:
            what += f"; motion codes refined by {method['refine_steps']} steps" if method["refine_steps"] != "0" \
                else "; motion codes not refined"
        notes.append(f"{name}: {what}.")
    notes += doc.get("remarks", [])
    if doc["silhouettes"]:
        grids = cfg.get("code_grids", 1)
        notes.append(f"Silhouettes: codes of {cfg['code_samples']} windows of distinct motions × "
                     f"{cfg['code_samples']} characters × up to {cfg['code_samples']} views of the split (pitch 0); "
                     f"mean ± standard error over {grids} such grids, each with its own motions and characters; "
                     "~1 = clusters by the label, ~0 = the label does not explain the codes. Plots: codes_*.png, "
                     "the first grid's codes along their first two principal components.")  # fmt: skip
        if cfg.get("probe_steps", 0) and PROBE_ROW in doc["silhouettes"]:
            notes.append(f"proportion probe: not a retargeting method but a reference point for the skeleton codes: a "
                         f"small convolutional network trained for {cfg['probe_steps']} steps on windows of the "
                         "training split, prepared as the first network's inputs, to read nothing but each "
                         "character's bone lengths over its height; its outputs are scored on the same grids as a "
                         "skeleton code.")  # fmt: skip
    return notes
