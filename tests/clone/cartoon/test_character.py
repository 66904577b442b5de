import json

import numpy as np
import pytest

from clone.cartoon.character import PARTS, PRESETS, STANDARD, CharacterSpec, load_character
from pose_io import InputError
from retarget.world.skeleton import BONE_NAMES


def test_presets_load_by_name_and_exaggerate_their_part():
    assert set(PRESETS) >= {"bighead", "stubby", "longarms", "chibi"}
    for name in PRESETS:
        assert load_character(name) is PRESETS[name]
    standard = load_character("standard").skeleton()
    np.testing.assert_allclose(standard.array, STANDARD.array)
    assert load_character("bighead").skeleton().length("head") == pytest.approx(2 * STANDARD.length("head"))
    assert load_character("stubby").skeleton().leg_length < 0.6 * STANDARD.leg_length
    assert load_character("longarms").skeleton().length("l_wrist") > 1.4 * STANDARD.length("l_wrist")


def test_overlapping_parts_multiply_and_scale_acts_on_every_bone():
    spec = CharacterSpec("x", {"arms": 2.0, "forearms": 1.5}, scale=0.5)
    factors = spec.bone_factors()
    assert factors["l_wrist"] == pytest.approx(1.5) and factors["l_elbow"] == pytest.approx(1.0)
    assert factors["neck"] == pytest.approx(0.5) and set(factors) == set(BONE_NAMES)
    assert all(set(bones) <= set(BONE_NAMES) for bones in PARTS.values())


def test_json_file_round_trips(tmp_path):
    path = tmp_path / "mine.json"
    path.write_text(json.dumps({"name": "tiny legs", "legs": 0.5, "head": 1.5, "scale": 0.9}))
    spec = load_character(path)
    assert spec.name == "tiny legs" and spec.factors == {"legs": 0.5, "head": 1.5} and spec.scale == 0.9
    path.write_text(json.dumps(spec.to_dict()))
    assert load_character(str(path)) == spec
    (tmp_path / "plain.json").write_text('{"arms": 1.2}')
    assert load_character(tmp_path / "plain.json").name == "plain"


@pytest.mark.parametrize("content, message", [
    ("{not json", "cannot read"),
    ("[1, 2]", "JSON object"),
    ('{"tail": 2.0}', "unknown parts tail"),
    ('{"legs": -1}', "legs must be a number"),
    ('{"legs": 40}', "legs must be a number"),
    ('{"legs": "short"}', "legs must be a number"),
    ('{"legs": true}', "legs must be a number"),
    ('{"scale": 0}', "scale must be a number"),
    ('{"name": 3}', "name must be"),
])
def test_bad_json_is_an_input_error(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(InputError, match=message) as info:
        load_character(path)
    assert str(path) in str(info.value)


def test_unknown_name_lists_the_presets(tmp_path):
    with pytest.raises(InputError, match="not a preset .*bighead.* nor a JSON file"):
        load_character("giraffe")
    with pytest.raises(InputError, match="not a preset"):
        load_character(tmp_path / "missing.json")
