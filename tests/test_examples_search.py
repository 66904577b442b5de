"""examples/search.sh runs here on tiny OpenPose folders built in tmp_path (see tests/test_examples.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FRAMES = 120
PERIOD = 32  # the tall walker's stride (tests/figures.py): a cut also matches one stride earlier or later


def _search_registered() -> bool:
    from clone.cli.main import app

    return any(group.name == "search" for group in app.registered_groups)


def _path_with_clone(tmp_path: Path) -> str:
    """PATH whose `clone` has the `search` commands: the venv's once registered, until then a stand-in."""
    path = f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
    if _search_registered():
        return path
    shim = tmp_path / "bin" / "clone"
    shim.parent.mkdir()
    shim.write_text(
        f"#!{sys.executable}\n"
        "from clone.cli.main import app\n"
        "from clone.cli.search import search_app\n"
        "app.add_typer(search_app, name='search')\n"
        "app()\n"
    )
    shim.chmod(0o755)
    return f"{shim.parent}{os.pathsep}{path}"


def _near(value: int, target: int) -> bool:
    off = (value - target) % PERIOD
    return min(off, PERIOD - off) <= 2


def test_search_example(tmp_path):
    from pose_io.writers import write_track
    from tests.figures import tall_and_small

    examples = tmp_path / "openpose_examples"
    for name, track in tall_and_small(FRAMES).items():
        write_track(track, examples / f"{name}_man")
    out = tmp_path / "out"
    env = {**os.environ, "PATH": _path_with_clone(tmp_path)}
    result = subprocess.run(["bash", str(EXAMPLES / "search.sh"), str(examples), str(out), "720x720"], cwd=tmp_path,
                            env=env, capture_output=True, text=True, timeout=600, check=False)  # fmt: skip
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert "wrote" in result.stdout and "rank" in result.stdout
    hits = json.loads((out / "hits.json").read_text())["hits"]
    assert len(hits) == 3
    found = {Path(h["path"]).name: h for h in hits}
    assert set(found) == {"tall_man", "tall_man_shifted", "small_man"}
    assert {Path(h["path"]).name for h in hits[:2]} == {"tall_man", "tall_man_shifted"}
    assert _near(found["tall_man"]["start"], 40) and _near(found["tall_man_shifted"]["start"], 20)
    assert hits[0]["score"] > 0.8 and found["small_man"]["score"] < hits[1]["score"] - 0.2
