"""OPW parameters read from an arm's own axes, checked against the numbers of its URDF by hand,
and the measured deviation that decides OPW or KDL for Tesseract."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from usar_arm.planning.robot import robot_from_files
from usar_arm.urdf.description_reader import parse_urdf
from usar_arm.urdf.opw_fit import NotOpwError, fit_opw, opw_forward
from usar_arm.urdf.tesseract import TesseractOptions, choose_solver

ROOT = Path(__file__).resolve().parents[2]
AS_LEARNT = ROOT / "robots" / "generated" / "as-learnt"


def _spherical_wrist_chain():  # type: ignore[no-untyped-def]
    text = (AS_LEARNT / "KR60.urdf").read_text().replace(
        '<origin xyz="0.152 0.07 0" rpy="0 0 0"/>', '<origin xyz="0.152 0.068 0" rpy="0 0 0"/>')
    return parse_urdf(text)[0]


def test_the_spherical_wrist_kr60_has_the_parameters_its_urdf_gives_by_hand() -> None:
    # Joint origins (URDF, m): a1 (0.07, -0.01, 0.413), a2 +(0.424, 0.21, 0.383),
    # a3 +(-0.004, -0.06, 1.004), a4 +(0.491, -0.162, 0.169), a5 +(0.492, -0.068, 0),
    # a6 +(0.152, 0.068, 0) (the wrist made spherical), flange +0.05 along x.
    fit = fit_opw(_spherical_wrist_chain())
    p = fit.parameters
    assert fit.base[:3, 3] == pytest.approx([0.07, -0.01, 0.0], abs=1e-12)  # foot of axis 1
    assert np.allclose(fit.base[:3, :3], np.eye(3), atol=1e-12)
    assert p.a1 == pytest.approx(0.424, abs=1e-12)
    assert p.c1 == pytest.approx(0.413 + 0.383, abs=1e-12)
    assert p.c2 == pytest.approx(math.hypot(0.004, 1.004), abs=1e-12)
    assert p.a2 == pytest.approx(-0.169, abs=1e-12)  # the wrist sits 0.169 above joint 3
    assert p.c3 == pytest.approx(0.491 + 0.492, abs=1e-12)
    assert p.b == pytest.approx(0.21 - 0.06 - 0.162, abs=1e-12)  # wrist y from axis 1's
    assert p.c4 == pytest.approx(0.152 + 0.05, abs=1e-12)
    assert p.sign_corrections == (1, -1, -1, 1, 1, -1)  # joints a2, a3, a6 turn about -y, -x
    assert p.offsets[2] == pytest.approx(-math.pi / 2 - math.atan2(0.004, 1.004), abs=1e-12)
    assert fit.wrist_gap_m < 1e-12
    # tool0 is turned by 1.570796327 (the URDF's 10 digits), not pi/2: a 2e-10 rad tilt.
    assert fit.position_error_m < 1e-12 and fit.rotation_error_rad < 1e-9


def test_the_usarsim_kr60_is_3_mm_from_opw_because_its_wrist_axes_pass_2_mm_apart() -> None:
    fit = fit_opw(robot_from_files(AS_LEARNT / "KR60.urdf").chain)
    # joint_a6's origin is 0.07 m across the forearm where joint_a4's axis runs at 0.068 m
    assert fit.wrist_gap_m == pytest.approx(0.002, abs=1e-9)
    assert fit.wrist_gap_joints == ("joint_a4", "joint_a6")
    assert 2.5e-3 < fit.position_error_m < 3.5e-3
    assert not fit.within(1e-6, 1e-6) and fit.within(5e-3, 1e-6)


def test_the_docs_give_the_figures_the_tool_measures() -> None:
    """The Tesseract section of docs/moveit-tesseract.md quotes the wrist gap and OPW's deviation
    of the as-learnt and the calibrated KR60 to two digits, as tesseract-config reports them."""
    text = " ".join((ROOT / "docs" / "moveit-tesseract.md").read_text().split())
    quoted = re.search(r"the axes of its joints a4 and a6 pass ([0-9.]+) mm apart \(([0-9.]+) mm "
                       r"in the calibrated description\), so OPW would put tool0 up to ([0-9.]+) "
                       r"mm off \(([0-9.]+) mm calibrated\)", text)
    assert quoted, "the docs' sentence on the KR60 and OPW changed: update this test"
    chains = [robot_from_files(d / "KR60.urdf").chain for d in (AS_LEARNT, AS_LEARNT.parent)]
    fits = [fit_opw(chain) for chain in chains]
    measured = [*(f.wrist_gap_m for f in fits), *(f.position_error_m for f in fits)]
    assert list(quoted.groups()) == [f"{m * 1e3:.1f}" for m in measured]
    for chain, gap in zip(chains, quoted.groups()[:2], strict=True):
        reason = choose_solver(chain, TesseractOptions())[1]
        assert f"joint_a4 and joint_a6 pass {gap} mm apart" in reason, reason


def test_opw_forward_at_zero_is_the_arm_standing_up() -> None:
    fit = fit_opw(_spherical_wrist_chain())
    p = fit.parameters
    zero_opw = [o * s for o, s in zip(p.offsets, p.sign_corrections, strict=True)]
    up = opw_forward(p, zero_opw)  # every OPW angle 0
    assert up[:3, 3] == pytest.approx([p.a1 + p.a2, p.b, p.c1 + p.c2 + p.c3 + p.c4], abs=1e-12)
    assert np.allclose(up[:3, :3], np.eye(3), atol=1e-12)


def test_an_arm_with_a_rail_is_refused_with_the_reason() -> None:
    text = (AS_LEARNT / "KR60.urdf").read_text().replace(
        '<joint name="joint_a1" type="revolute">', '<joint name="joint_a1" type="prismatic">')
    with pytest.raises(NotOpwError, match="not revolute: joint_a1"):
        fit_opw(parse_urdf(text)[0])
