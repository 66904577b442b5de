"""Evaluation of 2D retargeting on the motion world: the error table and the code silhouettes.

Protocol. A *case* moves the motion of window ``mA`` performed by character ``cA`` and seen by camera A onto
character ``cB`` seen by camera B (``cA != cB``; each camera is one of the 13 view bins, or of those within
+-``max_yaw`` degrees of the front, with a pitch drawn uniformly in +-``max_pitch`` degrees; every choice comes
from one seeded generator). The ground truth is the
world's own answer: the same 3D motion replayed on ``cB`` (``retarget_3d``: every bone keeps its direction and
takes ``cB``'s length, the root path is scaled by the leg ratio, the feet stay on the ground) and projected
by camera B with the framing rule - ``WorldSplit.window(mA, cB, vB)``.

What a method learns about B comes only from a *reference*: another window of the split, performed by ``cB``
and seen by camera B, of another motion (another motion group when the split has one, else frames that do
not overlap the evaluated ones), as a user's reference video would show it. Networks take their skeleton and
view codes and their placement from it, the 2D baselines their scale statistics.

Sources of cases: the split's own windows (for ``test``: motions and characters never seen in training) and,
optionally, extra mocap clips replayed on the same characters (:class:`ClipMotions`), still with references
from the split.

Metrics (:func:`pose_errors`), with coordinates divided by the target's height ``h`` in pixels (the height of
``cB``'s skeleton times the camera's pixels per metre): the paper's error, the mean over frames, joints and
both coordinates of the squared difference, shown x 10^3 (units h^2 x 10^-3); RMSE, the root mean squared
joint distance of a case in % of ``h``; PCK@a, the share of joints within ``a h`` of the truth. Each is
reported three ways (:data:`ALIGNMENTS`): ``pose`` (each frame's MidHip subtracted from prediction and truth,
the 14 other joints scored: the paper's numbers are about the pose), ``with_root`` (one translation per case
removed, the least-squares one, so the root trajectory counts but not where in the frame the reference
stood) and ``placed`` (the output as it lands in the reference's frame).

Rows: the networks (ours, ``--compare`` checkpoints, the authors' released models), the 2D baselines of
:mod:`retarget.baselines.methods`, and three 3D references that see the 3D truth (:data:`REFERENCES_3D`).

Modules: :mod:`~retarget.evaluate.config` (what is evaluated), :mod:`~retarget.evaluate.scores` (one case's
scores and their summary), :mod:`~retarget.evaluate.references3d`, :mod:`~retarget.evaluate.cases` (sampling
and the evaluation loop), :mod:`~retarget.evaluate.codes` (silhouettes and their plots),
:mod:`~retarget.evaluate.probe` (a proportion probe, the reference point for the skeleton codes' silhouette),
:mod:`~retarget.evaluate.real` (real-track pairs, no ground truth), :mod:`~retarget.evaluate.report` (eval.md)
and :mod:`~retarget.evaluate.run` (the rows and the output folder).
"""

from retarget.evaluate.cases import Case, ClipMotions, evaluate, sample_cases
from retarget.evaluate.codes import code_silhouettes, pca_2d, plot_codes, silhouette
from retarget.evaluate.config import EvalConfig, Method, Progress
from retarget.evaluate.real import markdown_rows, pair_scores, real_pair_results, wrist_rise
from retarget.evaluate.references3d import (
    REFERENCE_FUNCTIONS,
    REFERENCES_3D,
    global_scale_3d,
    naive_copy_3d,
    rotation_copy_3d,
)
from retarget.evaluate.report import markdown_report, report_notes
from retarget.evaluate.run import BASELINES, DESCRIPTIONS, OFFICIAL_FILES, network_method, run_eval
from retarget.evaluate.scores import (
    ALIGNMENTS,
    METRICS,
    case_scores,
    offset_aligned,
    pose_errors,
    root_aligned,
    summarise,
)

__all__ = [
    "ALIGNMENTS",
    "BASELINES",
    "DESCRIPTIONS",
    "METRICS",
    "OFFICIAL_FILES",
    "REFERENCES_3D",
    "REFERENCE_FUNCTIONS",
    "Case",
    "ClipMotions",
    "EvalConfig",
    "Method",
    "Progress",
    "case_scores",
    "code_silhouettes",
    "evaluate",
    "global_scale_3d",
    "markdown_report",
    "markdown_rows",
    "naive_copy_3d",
    "network_method",
    "offset_aligned",
    "pair_scores",
    "pca_2d",
    "plot_codes",
    "pose_errors",
    "real_pair_results",
    "report_notes",
    "root_aligned",
    "rotation_copy_3d",
    "run_eval",
    "sample_cases",
    "silhouette",
    "summarise",
    "wrist_rise",
]
