"""examples/search.sh runs here on tiny OpenPose folders built in tmp_path (see tests/test_examples.py)."""

from __future__ import annotations

import json
from pathlib import Path

from tests.examples_support import EXAMPLES, run_example, write_people

FRAMES = 120
PERIOD = 32  # the tall walker's stride (tests/figures.py): a cut also matches one stride earlier or later


def _near(value: int, target: int) -> bool:
    off = (value - target) % PERIOD
    return min(off, PERIOD - off) <= 2


def test_search_example(tmp_path):
    examples = write_people(tmp_path / "openpose_examples", FRAMES)
    out = tmp_path / "out"
    result = run_example(["bash", str(EXAMPLES / "search.sh"), str(examples), str(out), "720x720"], tmp_path)
    assert "wrote" in result.stdout and "rank" in result.stdout
    hits = json.loads((out / "hits.json").read_text())["hits"]
    assert len(hits) == 3
    found = {Path(h["path"]).name: h for h in hits}
    assert set(found) == {"tall_man", "tall_man_shifted", "small_man"}
    assert {Path(h["path"]).name for h in hits[:2]} == {"tall_man", "tall_man_shifted"}
    assert _near(found["tall_man"]["start"], 40) and _near(found["tall_man_shifted"]["start"], 20)
    assert hits[0]["score"] > 0.8 and found["small_man"]["score"] < hits[1]["score"] - 0.2
