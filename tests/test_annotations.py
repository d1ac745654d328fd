"""The annotation file (`mocap-annotations`): checking that names the bad place, sticky
resolution, atomic saving, and a fuzz test of the loader."""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mocap.body import SEGMENT_INDEX
from mocap.errors import MocapError
from mocap.io.annotations import Annotations, annotations_from_text, load_annotations, save_annotations
from mocap.lift.orientation import held_user_signs
from mocap.synth.oracle import annotations_for_poses
from mocap.synth.walk import walk_cycle

CONTRACT_EXAMPLE = {
    "format": "mocap-annotations",
    "version": 1,
    "keyframes": [0, 5, 10],
    "frames": {
        "0": {"orientation": "right", "foreshortening": {"upper_arm_l": "away", "lower_leg_r": "toward"}},
        "10": {"foreshortening": {"upper_arm_l": "toward"}, "joints2d": {"wrist_r": [312.5, 140.0]}},
    },
}


def parse(doc, frames: int | None = 20) -> Annotations:
    return annotations_from_text(json.dumps(doc), frames, "A.json")


def test_the_contract_example_resolves_sticky():
    notes = parse(CONTRACT_EXAMPLE)
    assert notes.keyframe_indices(20) == [0, 5, 10]
    assert notes.orientations(12) == ["right"] * 12
    values, since = notes.held_signs(12)
    arm = SEGMENT_INDEX["upper_arm_l"]
    assert values[:10, arm].tolist() == [-1] * 10 and values[10:, arm].tolist() == [1, 1]
    assert since[9, arm] == 0 and since[11, arm] == 10
    assert (values[:, SEGMENT_INDEX["lower_leg_r"]] == 1).all()
    assert (values[:, SEGMENT_INDEX["torso"]] == 0).all()
    assert notes.overrides() == {10: {"wrist_r": (312.5, 140.0)}}


def test_the_method_is_kept_through_a_save():
    notes = parse({**CONTRACT_EXAMPLE, "method": "track"})
    assert notes.method == "track" and parse(notes.to_dict()) == notes
    assert parse(CONTRACT_EXAMPLE).method is None and "method" not in parse(CONTRACT_EXAMPLE).to_dict()
    assert notes.with_method(None).to_dict() == parse(CONTRACT_EXAMPLE).to_dict()
    with pytest.raises(MocapError, match="unknown method 'optical'"):
        notes.with_method("optical")


def test_the_background_is_kept_through_a_save(tmp_path):
    for value, kept in (("plate.jpg", "plate.jpg"), ([0, 12], (0, 12))):
        notes = parse({**CONTRACT_EXAMPLE, "background": value})
        assert notes.background == kept
        path = save_annotations(tmp_path / "a.json", notes)
        assert load_annotations(path, 20) == notes and json.loads(path.read_text())["background"] == value
    notes = parse({**CONTRACT_EXAMPLE, "background": "plates/empty.png"})
    assert notes.background_source(tmp_path / "a.json") == str(tmp_path / "plates" / "empty.png")
    assert notes.with_background(None).to_dict() == parse(CONTRACT_EXAMPLE).to_dict()
    assert notes.with_background((2, 4)).background == (2, 4)
    with pytest.raises(MocapError, match="not a range"):
        notes.with_background((4, 2))


def test_keyframes_default_to_every_frame_and_orientation_holds_until_changed():
    notes = parse(
        {
            "format": "mocap-annotations",
            "version": 1,
            "frames": {"3": {"orientation": "left"}, "7": {"orientation": "backward_right"}},
        }
    )
    assert notes.keyframes is None and notes.keyframe_indices(4) == [0, 1, 2, 3]
    assert notes.orientations(9) == [None] * 3 + ["left"] * 4 + ["backward_right"] * 2


def test_a_held_sign_holds_until_a_later_entry_changes_it():
    """Sticky, as CONTRACT.md has it: frame 2's "toward" holds until frame 6 says "away"."""
    notes = Annotations().with_foreshortening(2, "torso", "toward").with_foreshortening(6, "torso", "away")
    values, since = notes.held_signs(9)
    assert held_user_signs(values, since)[:, 0].tolist() == [0, 0, 1, 1, 1, 1, -1, -1, -1]


@pytest.mark.parametrize(
    "doc, message",
    [
        ({"format": "mocap-motion", "version": 1}, 'A.json: format: expected "mocap-annotations"'),
        ({"format": "mocap-annotations", "version": 2}, "A.json: version: expected 1, got 2"),
        ({"format": "mocap-annotations", "version": True}, "A.json: version: expected 1, got true"),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"12": {"foreshortening": {"upper_leg": "away"}}}},
            'A.json: frames["12"].foreshortening: unknown segment "upper_leg"',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"1": {"joints2d": {"hand_l": [1, 2]}}}},
            'A.json: frames["1"].joints2d: unknown joint "hand_l"',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"1": {"orientation": "up"}}},
            'A.json: frames["1"].orientation: unknown orientation "up"',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"20": {"orientation": "left"}}},
            'A.json: frames["20"]: frame 20 is out of range (the video has 20 frames)',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"-1": {}}},
            'A.json: frames["-1"]: frame key "-1" is not a frame index',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "keyframes": [0, 25]},
            "A.json: keyframes[1]: frame 25 is out of range",
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"2": {"joints2d": {"knee_l": [1, "x"]}}}},
            'A.json: frames["2"].joints2d.knee_l: expected [x, y] in pixels',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"2": {"foreshortening": {"head": "near"}}}},
            'A.json: frames["2"].foreshortening.head: expected "toward" or "away"',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "frames": {"2": {"joint2d": {}}}},
            'A.json: frames["2"]: unknown key "joint2d"',
        ),
        ([1, 2], "A.json: expected a JSON object, got a list"),
        (
            {"format": "mocap-annotations", "version": 1, "method": "optical"},
            'A.json: method: expected one of silhouette, track, got "optical"',
        ),
        (
            {"format": "mocap-annotations", "version": 1, "background": [3, 25]},
            "A.json: background: frame 25 is out of range (the video has 20 frames)",
        ),
        (
            {"format": "mocap-annotations", "version": 1, "background": [5, 2]},
            "A.json: background: frames 5..2 are not a range",
        ),
        ({"format": "mocap-annotations", "version": 1, "background": ""}, "A.json: background: empty file name"),
        (
            {"format": "mocap-annotations", "version": 1, "background": {"file": "a.png"}},
            "A.json: background: expected a file name or [first, last] frames, got an object",
        ),
    ],
)
def test_bad_annotations_name_the_place(doc, message):
    with pytest.raises(MocapError) as err:
        parse(doc)
    assert str(err.value).startswith(message), str(err.value)


@pytest.mark.parametrize(
    "text, message",
    [
        ("{", "A.json: not valid JSON"),
        ('{"format": "mocap-annotations", "version": 1, "frames": {"1": {}, "1": {}}}', 'duplicate key "1"'),
        (
            '{"format": "mocap-annotations", "version": 1, "frames": {"1": {"joints2d": {"neck": [NaN, 1]}}}}',
            "NaN is not a JSON number",
        ),
        (
            '{"format": "mocap-annotations", "version": 1, "frames": {"1": {"joints2d": {"neck": [1e999, 1]}}}}',
            'frames["1"].joints2d.neck: expected [x, y]',
        ),
    ],
)
def test_bad_json_is_refused(text, message):
    with pytest.raises(MocapError, match="^A.json: ") as err:
        annotations_from_text(text, 20, "A.json")
    assert message in str(err.value)


def test_save_and_load_round_trip_atomically(tmp_path):
    path = tmp_path / "a.json"
    notes = (
        parse(CONTRACT_EXAMPLE)
        .with_orientation(4, "forward_left")
        .with_foreshortening(4, "head", "away")
        .with_joint(6, "ankle_l", (10.0, 20.5))
    )
    save_annotations(path, notes)
    assert load_annotations(path, 20) == notes
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]
    cleared = notes.with_joint(6, "ankle_l", None).with_foreshortening(4, "head", None)
    assert 6 not in cleared.frames and cleared.frames[4].foreshortening == {}


def test_a_refused_file_changes_nothing(tmp_path):
    path = tmp_path / "a.json"
    text = json.dumps({"format": "mocap-annotations", "version": 1, "frames": {"99": {}}})
    path.write_text(text)
    with pytest.raises(MocapError, match="out of range"):
        load_annotations(path, 20)
    assert path.read_text() == text
    with pytest.raises(MocapError, match="no such annotation file"):
        load_annotations(tmp_path / "missing.json", 20)


def test_editing_refuses_unknown_names():
    with pytest.raises(MocapError, match="unknown orientation"):
        Annotations().with_orientation(0, "sideways")
    with pytest.raises(MocapError, match="unknown segment"):
        Annotations().with_foreshortening(0, "tail", "away")
    with pytest.raises(MocapError, match="unknown joint"):
        Annotations().with_joint(0, "nose", (1, 2))


def test_annotations_written_for_known_poses_say_what_they_show():
    joints = walk_cycle(1.0, 15.0)  # faces +z: the camera, turned neither way
    notes = annotations_for_poses(joints)
    assert notes.orientations(len(joints))[0].startswith("forward_")
    values, _ = notes.held_signs(len(joints))
    assert (values != 0).all()


# -- fuzzing: whatever the input, the loader answers with Annotations or one MocapError --

_json = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-3, 40)
    | st.floats(allow_nan=False)
    | st.text(max_size=12)
    | st.sampled_from(
        [
            "format",
            "version",
            "frames",
            "keyframes",
            "mocap-annotations",
            "left",
            "toward",
            "upper_arm_l",
            "wrist_r",
            "orientation",
            "foreshortening",
            "joints2d",
            "0",
            "12",
        ]
    ),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.sampled_from(
                [
                    "format",
                    "version",
                    "frames",
                    "keyframes",
                    "0",
                    "3",
                    "12",
                    "orientation",
                    "foreshortening",
                    "joints2d",
                    "upper_arm_l",
                    "head",
                    "wrist_r",
                    "x",
                ]
            )
            | st.text(max_size=6),
            inner,
            max_size=4,
        )
    ),
    max_leaves=20,
)


def _nested(frame: dict) -> dict:
    return {"format": "mocap-annotations", "version": 1, "frames": {"3": frame}}


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.one_of(
        _json,
        _json.map(_nested),
        st.dictionaries(st.sampled_from(["orientation", "foreshortening", "joints2d"]), _json, max_size=3).map(_nested),
    )
)
def test_the_loader_only_ever_raises_mocap_errors(doc):
    try:
        result = annotations_from_text(json.dumps(doc), 20, "A.json")
    except MocapError as exc:
        assert str(exc).startswith("A.json: ")
    else:
        assert isinstance(result, Annotations)
        result.orientations(20), result.held_signs(20), result.overrides()


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=60) | st.binary(max_size=40).map(lambda b: b.decode("latin-1")))
def test_arbitrary_text_is_refused_in_one_line(text):
    try:
        annotations_from_text(text, 20, "A.json")
    except MocapError as exc:
        assert str(exc).startswith("A.json: ")
