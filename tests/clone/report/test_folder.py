"""The report folder rules: where a report may go, what it may replace, and that a failure leaves nothing."""

from __future__ import annotations

import numpy as np
import pytest

from clone.report.folder import MARKER, check_report_dir, report_dir
from clone.report.results import MethodResult
from clone.report.write import write_report
from pose_io import InputError
from tests.clone.report.helpers import make_methods


def test_report_dir_rules(tmp_path):
    methods, info, gt = make_methods(with_frames=False)
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "keep.txt").write_text("mine")
    with pytest.raises(InputError, match="not made by `clone report`"):
        write_report(plain, methods, info, gt, overwrite=True)
    assert (plain / "keep.txt").read_text() == "mine" and len(list(plain.iterdir())) == 1
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(InputError, match="not a report folder"):
        write_report(afile, methods, info, gt, overwrite=True)

    out = tmp_path / "rep"
    page = write_report(out, methods, info, gt)
    assert page == out / "report.html" and (out / MARKER).is_file()
    assert (out.stat().st_mode & 0o055) == 0o055  # readable by others, like any other output
    with pytest.raises(InputError, match="--overwrite"):
        write_report(out, methods, info, gt)
    (out / "old.txt").write_text("old")
    write_report(out, methods, info, gt, overwrite=True)
    assert not (out / "old.txt").exists() and (out / "report.html").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "plain", "rep"]  # no temp folders left


def test_failed_report_leaves_nothing(tmp_path):
    methods, info, gt = make_methods(with_frames=False)
    bad = {**methods, "retarget": MethodResult("R", methods["retarget"].poses, methods["retarget"].scores,
                                               {99: np.zeros((8, 8, 3), np.uint8)})}  # fmt: skip
    bad["global-scale"] = MethodResult("G", methods["global-scale"].poses, methods["global-scale"].scores,
                                       {99: np.zeros((8, 8, 3), np.uint8)})  # fmt: skip
    with pytest.raises(ValueError, match="past the driver"):
        write_report(tmp_path / "rep", bad, info, gt)
    assert list(tmp_path.iterdir()) == []


def test_report_dir_stage_becomes_the_folder(tmp_path):
    out = tmp_path / "rep"
    check_report_dir(out, overwrite=False)  # a new path is fine
    with report_dir(out) as stage:
        assert stage.parent == tmp_path and stage != out and list(stage.iterdir()) == []
        (stage / "a.txt").write_text("a")
        assert not out.exists()  # nothing in place before the block succeeds
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "a.txt"]
    check_report_dir(out, overwrite=True)  # a report may be replaced when asked

    with pytest.raises(RuntimeError, match="boom"), report_dir(out, overwrite=True) as stage:
        (stage / "b.txt").write_text("b")
        raise RuntimeError("boom")
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "a.txt"]  # the old report is untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]  # and the stage is gone

    link = tmp_path / "link"
    link.symlink_to(out)
    with pytest.raises(InputError, match="not a report folder"):
        check_report_dir(link, overwrite=True)  # a link to a report is not replaced through the link
