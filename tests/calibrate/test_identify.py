"""Identification on synthetic perturbed KR60 models with known answers (tests/calibrate/
synthetic.py makes them without the calibration code; Pinocchio is the truth's FK)."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings, tool_errors
from usar_arm.calibrate.identification import AUTO_MODEL, CalibrationOptions, identify
from usar_arm.calibrate.measurements import Measurement
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import FLIP_X, transform, transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

NOMINAL = KinematicModel(KR60)
TRACKER_BASE = transform_from_xyz_rpy([0.002, -0.001, 0.0015], [0.003, -0.002, 0.004])


@pytest.mark.parametrize("seed", [1, 2])
def test_tracker_file_target_50_poses_005mm_noise_gives_01mm_on_held_out_poses(
        seed: int) -> None:
    """The issue's file-mode target: 1 mm / 5 mrad per frame, 0.05 mm noise, 50 poses."""
    truth = perturbed(KR60, seed)
    fit_q, held_q = random_q(NOMINAL, 50, seed + 10), random_q(NOMINAL, 300, seed + 20)
    data = readings(truth, "tool0", TRACKER_BASE, fit_q, seed, sigma_m=5e-5, sigma_rad=5e-5)
    cal = identify(KR60, "tool0", data, np.eye(4))
    before = tool_errors(truth, TRACKER_BASE, KR60, np.eye(4), "tool0", held_q)
    after = tool_errors(truth, TRACKER_BASE, cal.apply(KR60), cal.base, "tool0", held_q)
    assert before[0] > 5e-3  # the perturbation matters
    assert after[0] <= 1e-4, f"tool0 {after[0] * 1e3:.3f} mm on held-out poses"
    assert after[1] <= 1e-4
    assert cal.consistent and not cal.rejected
    assert cal.rank == 30  # 6R arm, full pose measured, base and tool: 4 * 6 + 6
    held = readings(truth, "tool0", TRACKER_BASE, held_q[:40], seed + 1, sigma_m=5e-5,
                    sigma_rad=5e-5)
    val = cal.validate(KR60, "tool0", held)
    assert val.summary()["max_after_m"] < 3e-4 < val.summary()["max_before_m"]


def _axes(urdf: str) -> dict[str, np.ndarray]:
    """Each revolute joint's axis, read from the URDF text (xml.etree)."""
    root = ET.fromstring(urdf)
    return {j.get("name", ""): np.array(j.find("axis").get("xyz", "").split(), float)
            for j in root.findall("joint") if j.get("type") == "revolute"}


def _along(joint: str, axis: np.ndarray) -> set[str]:
    """The shift along and the rotation about a principal ``axis`` of ``joint``'s origin."""
    k = int(np.argmax(np.abs(axis)))
    assert np.abs(axis)[k] == 1.0  # the KR60's axes are principal
    return {f"{joint}.origin.{'xyz'[k]}", f"{joint}.origin.{('roll', 'pitch', 'yaw')[k]}"}


def test_unidentifiable_parameters_are_the_ones_kinematics_says_merge() -> None:
    """Full-pose readings of a 6R arm identify 4 x 6 + 6 = 30 of the 48 parameters. Which 18
    merge, from the chain alone: joint_a1's whole origin with the base (preferred, and rigidly
    attached before the first motion); for every later joint, the shift along and the rotation
    about the previous joint's axis (its origin is expressed in that joint's frame) with that
    joint's zero and shift; for joint_a6, also those along and about its own axis with the tool
    (preferred), which turns with it."""
    truth = perturbed(KR60, 3)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 50, 4), 5,
                    sigma_m=5e-5, sigma_rad=5e-5)
    cal = identify(KR60, "tool0", data, np.eye(4))
    axes = _axes(KR60)
    joints = [f"joint_a{k}" for k in range(1, 7)]
    expected = {f"joint_a1.origin.{a}" for a in ("x", "y", "z", "roll", "pitch", "yaw")}
    for previous, joint in itertools.pairwise(joints):
        expected |= _along(joint, axes[previous])
    expected |= _along("joint_a6", axes["joint_a6"])
    assert set(cal.unidentifiable) == expected and cal.rank == 30 and not cal.lost
    assert all(p.std > 0 and np.isfinite(p.std) for p in cal.parameters)
    assert cal.fit.summary()["max_after_m"] < 3e-4


def test_a_joint_that_never_moves_loses_the_next_frame_to_the_base() -> None:
    """joint_a1 held at 0.3 rad throughout: joint_a2's origin is then rigidly attached to the
    base, so the four of its parameters generic readings identify (all but those along and
    about joint_a1's axis) merge with the base: rank 26, and they are named as lost."""
    truth = perturbed(KR60, 3)
    q = random_q(NOMINAL, 50, 4)
    q[:, 0] = 0.3
    data = readings(truth, "tool0", TRACKER_BASE, q, 5, sigma_m=5e-5, sigma_rad=5e-5)
    cal = identify(KR60, "tool0", data, np.eye(4))
    generic = {f"joint_a2.origin.{a}" for a in ("x", "y", "z", "roll", "pitch", "yaw")} \
        - _along("joint_a2", _axes(KR60)["joint_a1"])
    assert set(cal.lost) == generic and cal.rank == 26 and cal.generic_rank == 30
    assert cal.consistent


def test_the_tool_points_stated_sigma_matches_its_scatter_over_noise_draws() -> None:
    """The report's 1-sigma of the tool point (from the covariance) against the test's own
    measure: the scatter of tool0's fitted position at the fitted configurations over 16 fits
    of the same configurations with fresh 0.05 mm / 0.05 mrad noise."""
    truth = perturbed(KR60, 5)
    q = random_q(NOMINAL, 50, 6)
    fits, stated = [], []
    for seed in range(16):
        data = readings(truth, "tool0", TRACKER_BASE, q, 100 + seed, sigma_m=5e-5,
                        sigma_rad=5e-5)
        cal = identify(KR60, "tool0", data, np.eye(4))
        model = KinematicModel(cal.apply(KR60))
        fits.append([(cal.base @ model.frame_pose(qk, "tool0"))[:3, 3] for qk in q])
        stated.append(cal.tool_sigma_m[0])
    scatter = np.sqrt(np.var(np.array(fits), axis=0, ddof=1).sum(axis=1))  # per configuration
    assert 0.6 < float(np.median(stated)) / float(np.median(scatter)) < 1.6, \
        (np.median(stated), np.median(scatter))


def test_a_fit_stopped_at_its_iteration_cap_is_not_consistent() -> None:
    truth = perturbed(KR60, 3)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 50, 4), 5,
                    sigma_m=5e-5, sigma_rad=5e-5)
    cal = identify(KR60, "tool0", data, np.eye(4), CalibrationOptions(max_iterations=1))
    assert not cal.converged and not cal.consistent
    assert cal.problems == ("the fit did not converge within 1 Levenberg-Marquardt "
                            "iterations",)


def test_position_only_readings_fit_without_the_rotation_numbers() -> None:
    truth = perturbed(KR60, 4)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 60, 5), 6, sigma_m=5e-5)
    data = [Measurement(m.q, m.position, None, sigma_m=m.sigma_m, label=m.label) for m in data]
    cal = identify(KR60, "tool0", data, np.eye(4))
    held_q = random_q(NOMINAL, 200, 7)
    after = tool_errors(truth, TRACKER_BASE, cal.apply(KR60), cal.base, "tool0", held_q)
    assert after[0] <= 2e-4 and cal.rank < 30  # orientation of the tool is not seen


def test_quantised_wire_readings_1mm_1mrad_reach_02mm_02mrad() -> None:
    """Readings of the tip sensor printed in the z-down world to 1 mm / 1 mrad; 200 readings
    at configurations whose numbers fall at different places inside their steps."""
    truth = perturbed(KR60, 1)
    base = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0015], [0.003, -0.002, 0.004])
    guess = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0], [0.0, 0.0, 0.0])
    data = readings(truth, "KR60ArmTipTruth", base, random_q(NOMINAL, 200, 11), 3,
                    step_m=1e-3, step_rad=1e-3)
    cal = identify(KR60, "KR60ArmTipTruth", data, guess)
    assert cal.quantisation == AUTO_MODEL and cal.consistent
    after = tool_errors(truth, base, cal.apply(KR60), cal.base, "KR60ArmTipTruth",
                        random_q(NOMINAL, 300, 5))
    assert after[0] <= 2e-4 and after[1] <= 2e-4, after


def test_a_lying_reading_is_rejected_by_label() -> None:
    truth = perturbed(KR60, 5)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 50, 6), 7,
                    sigma_m=5e-5, sigma_rad=5e-5)
    liar = data[17]
    data[17] = Measurement(liar.q, liar.position + np.array([0.004, 0, 0]), liar.rpy, sigma_m=5e-5,
                           sigma_rad=5e-5, label="the liar")
    cal = identify(KR60, "tool0", data, np.eye(4))
    assert cal.rejected == ("the liar",)
    honest = [k for k, lb in enumerate(cal.fit.labels) if lb != "the liar"]
    assert cal.consistent and cal.fit.after_m[honest].max() < 3e-4
    assert cal.fit.after_m[17] > 3e-3  # the lie stays visible in the report


def test_a_base_moved_mid_run_is_reported_inconsistent_naming_the_split() -> None:
    """Stated noise, the base moved 3 mm / 2 mrad after reading r24: the change point is r25."""
    truth = perturbed(KR60, 6)
    q = random_q(NOMINAL, 50, 8)
    moved = TRACKER_BASE @ transform_from_xyz_rpy([0.003, 0, 0], [0, 0, 0.002])
    data = (readings(truth, "tool0", TRACKER_BASE, q[:25], 1, sigma_m=5e-5, sigma_rad=5e-5)
            + readings(truth, "tool0", moved, q[25:], 2, sigma_m=5e-5, sigma_rad=5e-5))
    data = [Measurement(m.q, m.position, m.rpy, sigma_m=5e-5, sigma_rad=5e-5, label=f"r{k}")
            for k, m in enumerate(data)]
    cal = identify(KR60, "tool0", data, np.eye(4))
    assert not cal.consistent and cal.change is not None and cal.change.detected
    assert cal.change_label == "r25"


def test_a_base_moved_1mm_without_stated_noise_is_named_at_the_split() -> None:
    """No stated noise: the noise estimated from the scatter absorbs a 1 mm move (no reading
    scores as an outlier), the residuals in reading order do not. The split is at the first
    moved reading and the shift the fit leaves between the halves is about the move."""
    truth = perturbed(KR60, 6)
    q = random_q(NOMINAL, 50, 8)
    moved = TRACKER_BASE @ transform_from_xyz_rpy([0.001, 0, 0], [0, 0, 0])
    data = (readings(truth, "tool0", TRACKER_BASE, q[:25], 1, sigma_m=5e-5, sigma_rad=5e-5,
                     state_sigma=False)
            + readings(truth, "tool0", moved, q[25:], 2, sigma_m=5e-5, sigma_rad=5e-5,
                       state_sigma=False))
    data = [Measurement(m.q, m.position, m.rpy, label=f"r{k}") for k, m in enumerate(data)]
    cal = identify(KR60, "tool0", data, np.eye(4))
    assert not cal.consistent and not cal.rejected
    assert cal.change is not None and cal.change_label == "r25"
    assert 0.7e-3 < cal.change.size < 1.1e-3
    assert cal.problems[0].startswith("readings from r25 on sit 0.9 mm off those before")
    clean = readings(truth, "tool0", TRACKER_BASE, q, 1, sigma_m=5e-5, sigma_rad=5e-5,
                     state_sigma=False)
    assert identify(KR60, "tool0", clean, np.eye(4)).consistent


def test_too_few_poses_is_a_clear_error() -> None:
    truth = perturbed(KR60, 7)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 4, 9), 1, sigma_m=5e-5,
                    sigma_rad=5e-5)
    with pytest.raises(CalibrationError, match="too few readings") as info:
        identify(KR60, "tool0", data, np.eye(4))
    # a well-posed fit: 2 numbers per identifiable parameter, 2 x 30 / 6 numbers per reading
    assert info.value.readings == 4 and info.value.needed == 10


def test_an_unknown_frame_or_model_is_refused() -> None:
    data = readings(KR60, "tool0", np.eye(4), random_q(NOMINAL, 10, 1), 1)
    with pytest.raises(CalibrationError, match="no link 'tool9'"):
        identify(KR60, "tool9", data, np.eye(4))
    with pytest.raises(CalibrationError, match="unknown quantisation model"):
        identify(KR60, "tool0", data, np.eye(4), CalibrationOptions(quantisation="mean"))


def test_the_calibrated_urdf_is_deterministic_and_changes_only_origins() -> None:
    truth = perturbed(KR60, 8)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 40, 2), 3, sigma_m=5e-5,
                    sigma_rad=5e-5)
    a = identify(KR60, "tool0", data, np.eye(4))
    b = identify(KR60, "tool0", data, np.eye(4))
    assert a.apply(KR60) == b.apply(KR60)
    changed = [(x, y) for x, y in zip(KR60.splitlines(), a.apply(KR60).splitlines(),
                                      strict=True) if x != y]
    assert changed and all("<origin" in y and "<joint" not in y for _, y in changed)


def test_selected_poses_with_readings_nearby_truncated_reach_02mm() -> None:
    """The wire's way, roughly: 50 observability-selected poses and readings near each (a
    tour reads the sensor in motion: 4 per pose here, a few mrad apart), truncated."""
    from usar_arm.calibrate.observability import select_poses

    truth = perturbed(KR60, 2)
    base = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0015], [0.003, -0.002, 0.004])
    guess = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0], [0.0, 0.0, 0.0])
    poses = select_poses(KR60, "KR60ArmTipTruth", 50, lambda q: True, seed=4)
    rng = np.random.default_rng(4)
    q = np.array([p + rng.normal(0.0, 3e-3, 6) * (k > 0) for p in poses for k in range(4)])
    q = np.clip(q, NOMINAL.lower, NOMINAL.upper)
    data = readings(truth, "KR60ArmTipTruth", base, q, 5, step_m=1e-3, step_rad=1e-3)
    cal = identify(KR60, "KR60ArmTipTruth", data, guess)
    after = tool_errors(truth, base, cal.apply(KR60), cal.base, "KR60ArmTipTruth",
                        random_q(NOMINAL, 300, 5))
    assert after[0] <= 2e-4 and after[1] <= 2e-4, after


def test_a_sensor_at_the_tip_moves_the_flange_onto_the_calibrated_sensor() -> None:
    """The KR60's tip sensor hangs from link_6 at the Tip: with tip_joint the flange (and so
    tool0) takes the calibrated sensor position; the printed Tip offset is overridden."""
    truth = perturbed(KR60, 9)
    data = readings(truth, "KR60ArmTipTruth", TRACKER_BASE, random_q(NOMINAL, 50, 3), 4,
                    sigma_m=5e-5, sigma_rad=5e-5)
    cal = identify(KR60, "KR60ArmTipTruth", data, np.eye(4))
    moved = KinematicModel(cal.apply(KR60, tip_joint="joint_a6-flange"))
    for qk in random_q(NOMINAL, 20, 8):
        sensor = moved.frame_pose(qk, "KR60ArmTipTruth")[:3, 3]
        np.testing.assert_allclose(moved.frame_pose(qk, "tool0")[:3, 3], sensor, atol=1e-9)
    with pytest.raises(CalibrationError, match="must be fixed"):
        cal.apply(KR60, tip_joint="flange-tool0")


def _on_a_rail(urdf: str) -> str:
    """The KR60 on a 3 m linear rail along x: joint_a1 hangs from a carriage that a prismatic
    joint moves along base_link's x."""
    old = '<parent link="base_link"/>\n    <child link="link_1"/>'
    assert old in urdf
    urdf = urdf.replace(old, '<parent link="carriage"/>\n    <child link="link_1"/>')
    rail = ('  <link name="carriage"/>\n  <joint name="rail" type="prismatic">\n'
            '    <origin xyz="0 0 0" rpy="0 0 0"/>\n    <parent link="base_link"/>\n'
            '    <child link="carriage"/>\n    <axis xyz="1 0 0"/>\n'
            '    <limit lower="0" upper="3" effort="0" velocity="1"/>\n  </joint>\n')
    return urdf.replace("</robot>", rail + "</robot>")


def test_seven_joints_one_prismatic_reach_the_tracker_target() -> None:
    nominal = _on_a_rail(KR60)
    model = KinematicModel(nominal)
    truth = perturbed(nominal, 21)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(model, 60, 22), 23, sigma_m=5e-5,
                    sigma_rad=5e-5)
    cal = identify(nominal, "tool0", data, np.eye(4))
    after = tool_errors(truth, TRACKER_BASE, cal.apply(nominal), cal.base, "tool0",
                        random_q(model, 300, 24))
    assert after[0] <= 1e-4 and after[1] <= 1e-4, after
    assert cal.rank == 32  # a prismatic joint adds 2 (its direction), not 4


def test_readings_without_a_stated_uncertainty_get_the_noise_they_show() -> None:
    """A tracker file with no sigma column and 0.3 mm / 0.3 mrad of noise: consistent, and a
    lie of 4 mm is still rejected."""
    truth = perturbed(KR60, 13)
    data = readings(truth, "tool0", TRACKER_BASE, random_q(NOMINAL, 60, 14), 15, sigma_m=3e-4,
                    sigma_rad=3e-4, state_sigma=False)
    cal = identify(KR60, "tool0", data, np.eye(4))
    assert cal.consistent and not cal.rejected
    liar = data[5]
    data[5] = Measurement(liar.q, liar.position + np.array([0, 0.004, 0]), liar.rpy,
                          label="the liar")
    assert identify(KR60, "tool0", data, np.eye(4)).rejected == ("the liar",)


def test_truncated_joint_values_widen_the_intervals_instead_of_breaking_consistency() -> None:
    """Joint values printed to 4 decimals (0.1 mrad steps, as ASTA prints them): with step_q
    the fit stays consistent and within the target from 300 readings; the lever arm makes
    0.1 mrad up to 0.2 mm."""
    truth = perturbed(KR60, 1)
    base = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0015], [0.003, -0.002, 0.004])
    guess = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.0], [0.0, 0.0, 0.0])
    q = random_q(NOMINAL, 300, 11)
    data = readings(truth, "KR60ArmTipTruth", base, q, 3, step_m=1e-3, step_rad=1e-3)
    printed = [Measurement(np.trunc(m.q / 1e-4) * 1e-4, m.position, m.rpy, m.step_m,
                           m.step_rad, label=m.label, step_q=1e-4) for m in data]
    cal = identify(KR60, "KR60ArmTipTruth", printed, guess)
    assert cal.consistent and not cal.rejected
    after = tool_errors(truth, base, cal.apply(KR60), cal.base, "KR60ArmTipTruth",
                        random_q(NOMINAL, 300, 5))
    assert after[0] <= 2e-4 and after[1] <= 2e-4, after


def test_a_tracker_in_its_own_frame_is_registered_and_reaches_the_same_accuracy() -> None:
    """The tracker stands 2 m away, turned 100 degrees. Said to be in base_link (guess
    identity) the readings are refused as a base far from its guess; with no guess (the
    readings' frame unknown) the base is registered first and the fit reaches the target."""
    truth = perturbed(KR60, 2)
    tracker = transform_from_xyz_rpy([2.0, -1.0, 0.3], [0.1, -0.05, 1.75])
    data = readings(truth, "tool0", tracker, random_q(NOMINAL, 50, 12), 2, sigma_m=5e-5,
                    sigma_rad=5e-5)
    with pytest.raises(CalibrationError, match=r"as if the base were 225\d\.\d mm"):  # |2, -1, 0.3|
        identify(KR60, "tool0", data, np.eye(4))
    cal = identify(KR60, "tool0", data, None)
    assert cal.registered
    after = tool_errors(truth, tracker, cal.apply(KR60), cal.base, "tool0",
                        random_q(NOMINAL, 300, 22))
    assert cal.consistent and after[0] <= 1e-4 and after[1] <= 1e-4, after
