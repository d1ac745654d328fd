"""BVH reading and the mapping onto the 16 contract joints."""

from pathlib import Path

import numpy as np
import pytest

from mocap import body
from mocap.errors import MocapError
from mocap.io import bvh_reader as bvh

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
FILES = ["cmu_walk.bvh", "cmu_run.bvh", "cmu_01_01_jumps.bvh", "walk01.bvh"]

# Position channels on a non-root joint and two non-ZXY rotation orders.
SMALL = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
  JOINT Chest
  {
    OFFSET 0 10 0
    CHANNELS 6 Xposition Yposition Zposition Xrotation Zrotation Yrotation
    End Site
    {
      OFFSET 0 5 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3 0 0 0   0 10 0 0 0 0
1 0 0 90 0 0  5 0 0 90 90 0
"""


def test_small_file_positions():
    m = bvh.parse_bvh(SMALL)
    assert m.names == ("Hips", "Chest", "Chest_end")
    assert list(m.parents) == [-1, 0, 1] and list(m.end_site) == [False, False, True]
    assert m.frame_time == 0.5 and m.n_frames == 2
    pos = m.positions()
    np.testing.assert_allclose(pos[0], [[1, 2, 3], [1, 12, 3], [1, 17, 3]], atol=1e-9)
    # frame 1: root yawed 90 degrees, chest translated by its position channels (5, 0, 0)
    # -> (0, 0, -5) from the root; chest rotation is Rx(90) @ Rz(90) (listed order), so
    # its end offset (0, 5, 0) -> (-5, 0, 0) -> yawed to (0, 0, 5).
    np.testing.assert_allclose(pos[1], [[1, 0, 0], [1, 0, -5], [1, 0, 0]], atol=1e-9)


@pytest.mark.parametrize(
    "text, words",
    [
        ("hello", "not a BVH file"),
        (SMALL.replace("OFFSET 0 10 0", "OFFSET 0 ten 0"), "garbled HIERARCHY"),
        (SMALL.replace("Zrotation\n  JOINT", "Wrotation\n  JOINT"), "bad CHANNELS"),
        (SMALL.replace("1 0 0 90 0 0  5 0 0 90 90 0", "1 0 0 90"), "expected 2 frames x 12 channels"),
        (SMALL.replace("Frame Time: 0.5", "Frame Time: x"), "non-number"),
        (SMALL.replace("    }\n  }\n}", "    }\n  }\n"), "incomplete HIERARCHY"),
    ],
)
def test_garbled_text_gives_one_line_error(text, words):
    with pytest.raises(MocapError, match=words) as info:
        bvh.parse_bvh(text, source="x.bvh")
    assert "\n" not in str(info.value) and str(info.value).startswith("x.bvh")


def test_missing_file(tmp_path):
    with pytest.raises(MocapError, match="cannot read BVH file"):
        bvh.read_bvh(tmp_path / "absent.bvh")


def _data(name):
    path = DATA / name
    if not path.exists():
        pytest.skip(f"{path} absent (third-party data lives beside the checkout)")
    return bvh.read_bvh(path)


@pytest.mark.parametrize("name", FILES)
def test_contract_joints_of_real_files(name):
    motion = _data(name)
    joints = bvh.contract_joints(motion)
    j = body.JOINT_INDEX
    assert joints.shape == (motion.n_frames, 16, 3)
    assert body.body_height(joints[0]) == pytest.approx(1.75)
    y = joints[0, :, 1]
    assert y[j["head_top"]] > y[j["neck"]] > y[j["chest"]] > y[j["pelvis"]]
    assert y[j["pelvis"]] > max(y[j["ankle_l"]], y[j["ankle_r"]])
    # anatomical sides: the performer's left is left of where they travel
    forward = joints[-1, j["pelvis"]] - joints[0, j["pelvis"]]
    left = joints[0, j["hip_l"]] - joints[0, j["hip_r"]]
    assert np.cross([0.0, 1.0, 0.0], forward) @ left > 0


@pytest.mark.parametrize(
    "name, shoulder, wrist",
    [
        ("cmu_walk.bvh", "LeftShoulder", "LeftWrist"),  # DAZ: LeftShoulder is the upper arm
        ("cmu_run.bvh", "lShldr", "lHand"),
        ("cmu_01_01_jumps.bvh", "LeftArm", "LeftHand"),  # CMU: LeftShoulder is the collar
        ("walk01.bvh", "LeftArm", "LeftHand"),
    ],
)
def test_joint_names_per_style(name, shoulder, wrist):
    motion = _data(name)
    found = bvh.joint_map(motion)
    assert motion.names[found["shoulder_l"]] == shoulder
    assert motion.names[found["wrist_l"]] == wrist
    joints = bvh.contract_joints_units(motion)[:1]
    j = body.JOINT_INDEX
    np.testing.assert_allclose(joints[0, j["pelvis"]], joints[0, [j["hip_l"], j["hip_r"]]].mean(0))


def test_positions_agree_with_bvhio():
    bvhio = pytest.importorskip("bvhio")
    motion = _data("walk01.bvh")
    pos = motion.positions()
    root = bvhio.readAsHierarchy(str(DATA / "walk01.bvh"))
    for frame in (0, 37):
        root.loadPose(frame)
        for j, name in enumerate(motion.names):
            if not motion.end_site[j]:
                expected = np.array(root.filter(name)[0].PositionWorld)
                np.testing.assert_allclose(pos[frame, j], expected, atol=1e-3)
