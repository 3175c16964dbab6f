"""The generated description files: golden, valid, consistent, and named per the scheme."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK
from usar_arm.core.model import (
    Cylinder,
    Joint,
    JointLimits,
    JointType,
    KinematicChain,
    Link,
    Origin,
)
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions, Description, write_description
from usar_arm.planning.acm import adjacent_pairs
from usar_arm.urdf.moveit import moveit_files
from usar_arm.urdf.validation import find_check_urdf, semantic_problems

GOLDEN = Path(__file__).resolve().parents[2] / "robots" / "generated" / "as-learnt"
"""The as-learnt KR60 and Fanuc_M16iB20 (usar-arm urdf --no-calibrate): byte-identical on every
run."""
CALIBRATED = GOLDEN.parent
"""The calibrated KR60 and Fanuc_M16iB20 and the readings of the tours they were calibrated
from: a new tour gives new readings (the simulator's state at each reading depends on when each
streamed command arrived), the same readings give the same files byte for byte."""


@pytest.fixture(scope="module")
def kr60() -> Description:
    return describe(DescribeOptions())


@pytest.mark.slow
def test_regenerating_the_kr60_gives_byte_identical_files(kr60: Description,
                                                          tmp_path: Path) -> None:
    paths = write_description(kr60, tmp_path)
    for path in paths.values():
        golden = GOLDEN / path.name
        assert golden.exists(), f"{golden} is not checked in"
        assert path.read_bytes() == golden.read_bytes(), f"{path.name} differs from the golden"


FILES = ("discovery.json", "joint_limits.yaml", "readings.csv", "srdf", "urdf")


@pytest.mark.parametrize("robot", ["KR60", "Fanuc_M16iB20"])
def test_the_calibrated_descriptions_are_regenerated_byte_identically_from_their_readings(
        robot: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The command of docs/calibration.md (Reproducing a calibrated description): usar-arm
    urdf --robot ROBOT --readings robots/generated/ROBOT.readings.csv --out-dir
    robots/generated (the Fanuc's tour read a
    joint 1.2 mrad past its limit: the readings file must still be read back)."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    assert main(["urdf", "--robot", robot, "--readings",
                 str(CALIBRATED / f"{robot}.readings.csv"), "--out-dir", str(out)]) == EXIT_OK
    written = sorted(p.name for p in out.iterdir())
    assert written == [f"{robot}.{suffix}" for suffix in FILES]
    for name in written:
        assert (out / name).read_bytes() == (CALIBRATED / name).read_bytes(), \
            f"{name} differs from robots/generated/{name}"


def test_the_as_learnt_fanuc_is_regenerated_byte_identically(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """usar-arm urdf --robot Fanuc_M16iB20 --no-calibrate --out-dir robots/generated/as-learnt
    (the Fanuc on its rail, 7 joints)."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "out"
    assert main(["urdf", "--robot", "Fanuc_M16iB20", "--no-calibrate", "--out-dir", str(out),
                 "-q"]) == EXIT_OK
    written = sorted(p.name for p in out.iterdir())
    assert written == [f"Fanuc_M16iB20.{suffix}" for suffix in FILES if suffix != "readings.csv"]
    for name in written:
        assert (out / name).read_bytes() == (GOLDEN / name).read_bytes(), \
            f"{name} differs from robots/generated/as-learnt/{name}"


def test_check_urdf_accepts_the_urdf(kr60: Description, tmp_path: Path) -> None:
    f = tmp_path / "kr60.urdf"
    f.write_text(kr60.urdf)
    exe = find_check_urdf()
    assert exe is not None
    run = subprocess.run([exe, str(f)], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    assert "root Link: base_link" in run.stdout


def test_rep199_frames_and_tree(kr60: Description) -> None:
    chain = kr60.chain
    assert chain.root == "base_link"
    assert chain.frames == {"base_link": "base_link", "base": "base", "flange": "flange",
                            "tool0": "tool0", "tip_sensor": "KR60ArmTipTruth",
                            "tool_changer": "toolchange", "tool": "KR60gripper",
                            "tcp": "KR60gripper_tcp"}
    assert [j.name for j in chain.joints if j.type is JointType.FIXED] == [
        "base_link-base", "joint_a6-flange", "flange-tool0", "KR60ArmTipTruth_mount",
        "toolchange_mount", "KR60gripper_mount", "KR60gripper-KR60gripper_tcp"]
    for frame in ("base", "flange", "tool0"):
        assert not chain.link(frame).elements
    assert all(chain.link(f"link_{k}").elements for k in range(1, 7))


def test_link_cylinders_stay_out_of_their_neighbours(kr60: Description) -> None:
    # At the zero pose no pair of links collides except across a joint (adjacent), and the
    # collision matrix keeps real pairs enabled.
    assert kr60.acm.checked_pairs, "some link pairs must stay checked"
    reasons = {d.reason for d in kr60.acm.disabled}
    assert reasons <= {"Adjacent", "Default", "Always", "Never"}
    assert "Default" not in reasons and "Always" not in reasons


def test_srdf_group_home_and_matrix(kr60: Description) -> None:
    srdf = kr60.srdf
    assert '<robot name="KR60">' in srdf
    assert '<chain base_link="base_link" tip_link="tool0"/>' in srdf
    assert 'parent_frame="world" child_link="base_link"' in srdf
    assert "over 10000 random states, seed 0" in srdf
    for a, b in adjacent_pairs(kr60.chain):
        assert f'link1="{a}" link2="{b}" reason="Adjacent"' in srdf
    assert len(re.findall(r"<joint name=\"joint_a\d\" value=\"0\"/>", srdf)) == 6


def test_joint_limits_yaml_has_acceleration_and_jerk(kr60: Description) -> None:
    doc = yaml.safe_load(kr60.joint_limits)
    a2 = doc["joint_limits"]["joint_a2"]
    assert a2["has_acceleration_limits"] and a2["max_acceleration"] == pytest.approx(1.2)
    assert a2["has_jerk_limits"] and a2["max_jerk"] == pytest.approx(12.0)
    assert "estimate" in kr60.joint_limits


def test_moveit_package_is_complete_and_consistent(kr60: Description, tmp_path: Path) -> None:
    files = moveit_files(kr60.chain, kr60.urdf, kr60.srdf, kr60.joint_limits,
                         "KR60Arm_controller", kr60.home)
    expected = {".setup_assistant", "package.xml", "CMakeLists.txt", "config/KR60.urdf",
                "config/KR60.srdf", "config/KR60.urdf.xacro", "config/KR60.ros2_control.xacro",
                "config/initial_positions.yaml", "config/kinematics.yaml",
                "config/joint_limits.yaml", "config/pilz_cartesian_limits.yaml",
                "config/ros2_controllers.yaml", "config/moveit_controllers.yaml"}
    assert expected <= set(files)
    assert {f for f in files if f.startswith("launch/")} >= {"launch/demo.launch.py",
                                                           "launch/move_group.launch.py"}
    joints = list(kr60.chain.joint_names)
    ros2 = yaml.safe_load(files["config/ros2_controllers.yaml"])
    moveit = yaml.safe_load(files["config/moveit_controllers.yaml"])
    assert ros2["KR60Arm_controller"]["ros__parameters"]["joints"] == joints
    assert moveit["moveit_simple_controller_manager"]["KR60Arm_controller"]["joints"] == joints
    assert list(yaml.safe_load(files["config/initial_positions.yaml"])["initial_positions"]) \
        == joints
    assert set(yaml.safe_load(files["config/joint_limits.yaml"])["joint_limits"]) == set(joints)
    sa = yaml.safe_load(files[".setup_assistant"])["moveit_setup_assistant_config"]
    assert sa["URDF"]["package"] == "kr60_moveit_config"
    for name in re.findall(r'link[12]?="([^"]+)"', files["config/KR60.srdf"]):
        assert f'link name="{name}"' in kr60.urdf
    control = files["config/KR60.ros2_control.xacro"]
    assert re.findall(r'<joint name="([^"]+)">', control) == joints
    for text in (v for k, v in files.items() if k.endswith(".launch.py")):
        compile(text, "launch", "exec")


def test_moveit_xacro_expands_without_ros(kr60: Description, tmp_path: Path) -> None:
    import xacro  # the test extra installs it: a missing xacro is a failure, not a skip

    del xacro
    files = moveit_files(kr60.chain, kr60.urdf, kr60.srdf, kr60.joint_limits,
                         "KR60Arm_controller", kr60.home)
    for rel, text in files.items():
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text(text)
    import shutil
    import sys
    exe = shutil.which("xacro") or str(Path(sys.executable).parent / "xacro")
    run = subprocess.run([exe, str(tmp_path / "config" / "KR60.urdf.xacro")],
                         capture_output=True, text=True, check=False, cwd="/")
    assert run.returncode == 0, run.stderr
    assert run.stdout.count("<ros2_control") == 1 and 'joint name="joint_a6"' in run.stdout


def _chain(**changes: object) -> KinematicChain:
    lim = JointLimits(-1, 1, 1.0, 10)
    cyl = Cylinder(0.05, 0.3, Origin())
    links = [Link("base_link", cyl, (1, 0, 0, 1), "red"), Link("base"), Link("link_1", cyl,
             (1, 0, 0, 1), "red"), Link("flange"), Link("tool0")]
    joints = [Joint("j0", JointType.FIXED, "base_link", "base"),
              Joint("j1", JointType.REVOLUTE, "base_link", "link_1", limits=lim),
              Joint("j2", JointType.FIXED, "link_1", "flange"),
              Joint("j3", JointType.FIXED, "flange", "tool0")]
    frames = {"base_link": "base_link", "base": "base", "flange": "flange", "tool0": "tool0"}
    base = {"links": links, "joints": joints, "frames": frames}
    base.update(changes)
    return KinematicChain("t", tuple(base["links"]), tuple(base["joints"]), base["frames"])


def test_semantic_checks_catch_what_check_urdf_does_not() -> None:
    assert semantic_problems(_chain()) == []
    bad_limits = JointLimits(1, -1, 0.0, -5, acceleration=0.0)
    c = _chain(joints=[Joint("j0", JointType.FIXED, "base_link", "base"),
                       Joint("j1", JointType.REVOLUTE, "base_link", "link_1", axis=(0, 0, 2),
                             limits=bad_limits),
                       Joint("j1", JointType.FIXED, "link_1", "flange"),
                       Joint("j3", JointType.FIXED, "flange", "tool0")])
    problems = "\n".join(semantic_problems(c))
    for words in ("must be below upper", "velocity limit 0.0", "effort -5", "acceleration limit",
                  "unit length", "joint names must be unique: j1"):
        assert words in problems
    no_tool = _chain(frames={"base_link": "base_link", "base": "base", "flange": "flange"})
    assert "frame 'tool0' is missing" in "\n".join(semantic_problems(no_tool))
    grey = _chain(links=[Link("base_link", Cylinder(0.1, 0.1)), Link("base"),
                         Link("link_1"), Link("flange", Cylinder(0.1, 0.1), (1, 1, 1, 1), "w"),
                         Link("tool0")])
    problems = "\n".join(semantic_problems(grey))
    assert "link base_link: visible geometry needs a <material>" in problems
    assert "'flange' (flange) must not carry geometry" in problems


KERNEL_SETS = ("Sandybridge", "Haswell", "Prescott", "Zen", "SkylakeX")
"""OpenBLAS kernel sets (OPENBLAS_CORETYPE) that stand for other CPUs: before the numbers of
discovery.json were written with the precision they mean, each of the first three regenerated
the calibrated KR60's fitted parameters differently in their 11th-12th significant digit."""


def _assert_regenerated(robot: str, coretype: str, tmp_path: Path) -> None:
    """`usar-arm urdf --readings` in a fresh process under the kernel set ``coretype`` writes
    robots/generated's files byte for byte."""
    out = tmp_path / coretype
    env = {**os.environ, "OPENBLAS_CORETYPE": coretype,
           "USAR_ARM_CACHE": str(tmp_path / f"cache-{coretype}")}
    subprocess.run([sys.executable, "-m", "usar_arm", "urdf", "--robot", robot, "--readings",
                    str(CALIBRATED / f"{robot}.readings.csv"), "--out-dir", str(out), "-q"],
                   env=env, check=True, capture_output=True, timeout=300)
    for name in sorted(p.name for p in out.iterdir()):
        assert (out / name).read_bytes() == (CALIBRATED / name).read_bytes(), \
            f"{name} differs from robots/generated/{name} with OPENBLAS_CORETYPE={coretype}"


@pytest.mark.parametrize(("robot", "coretype"), [("KR60", "Sandybridge"),
                                                  ("Fanuc_M16iB20", "Haswell")])
def test_the_calibrated_description_is_the_same_with_another_cpus_blas_kernels(
        robot: str, coretype: str, tmp_path: Path) -> None:
    """What `usar-arm urdf --readings` writes does not depend on the CPU: the golden files
    were written on one machine, and another CPU's BLAS kernels (stood for here by an OpenBLAS
    kernel set) regenerate them byte for byte."""
    _assert_regenerated(robot, coretype, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["KR60", "Fanuc_M16iB20"])
@pytest.mark.parametrize("coretype", KERNEL_SETS)
def test_every_kernel_set_regenerates_the_calibrated_descriptions(
        robot: str, coretype: str, tmp_path: Path) -> None:
    if coretype in NEEDS_AVX512 and "avx512f" not in _cpu_flags():
        pytest.skip(f"OpenBLAS's {coretype} kernels need AVX-512, which this CPU lacks "
                    "(they die with an illegal instruction)")
    _assert_regenerated(robot, coretype, tmp_path)


NEEDS_AVX512 = frozenset({"SkylakeX"})


def _cpu_flags() -> set[str]:
    """The CPU's feature flags (Linux), empty where /proc/cpuinfo cannot be read."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    return {flag for line in text.splitlines() if line.startswith("flags")
            for flag in line.split(":", 1)[1].split()}
