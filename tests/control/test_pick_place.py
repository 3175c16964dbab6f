"""The demo's pick-and-place against the embedded simulator over real TCP: the part created
through the WorldController, gripped by the vacuum, carried around the tower as an attached
object and let go in the bin, judged by the simulator's GetSTA and contacts; and what goes
wrong: a grip over nothing (a typed error naming the move, nothing carried off in the
planner's world), the suction lost mid-move (the executor stops the arm)."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import numpy as np
import pytest

from usar_arm.arm.cell_session import CellSession
from usar_arm.arm.cycle import PLACE, MoveResult, pick_and_place, tcp_offset
from usar_arm.arm.facade import Arm
from usar_arm.arm.pick_place import PLACE_TOLERANCE_M, run_pick_place
from usar_arm.core.cell_errors import GripError
from usar_arm.core.errors import ExecutionAbortedError

pytestmark = pytest.mark.xdist_group("pick-place")


@pytest.fixture(scope="module")
def arm() -> Iterator[Arm]:
    with Arm.connect("KR60", wire_precision="full") as live:
        yield live


@pytest.fixture()
def cell(arm: Arm) -> Iterator[CellSession]:
    """The table cell built afresh (the objects go when the connection closes), the arm
    home."""
    assert arm.client is not None
    home = arm.plan(joints=arm.home, scene="table")
    arm.execute(home.trajectory)
    with CellSession(arm.client.host, arm.client.port, "table") as session:
        session.build()
        yield session


def test_the_part_is_picked_carried_and_rests_in_the_bin_with_no_contact(
        arm: Arm, cell: CellSession) -> None:
    moves = pick_and_place(arm.home, tcp_offset(arm.robot))
    done = run_pick_place(arm, cell, moves)
    p = done.placement
    assert p.gripped == "part"
    assert p.final_pose is not None and p.xy_error_m is not None
    assert p.xy_error_m <= PLACE_TOLERANCE_M, p.as_json()
    assert p.in_bin and p.placed, p.line()
    assert p.arm_contacts == [] and p.carried_contacts == []
    assert p.contact_reports > 100  # the contact truth was listening all along (10 Hz)
    assert p.line().startswith("part placed in the bin: yes (")
    # the planner carried it: the moves between grip and release were checked with the part
    assert [m.move.name for m in done.cycle.moves][2:5] == ["lift", "transfer", "place"]
    assert len(done.carried_goals) == 3
    assert done.carrying_chain is not None
    assert "part" in {lk.name for lk in done.carrying_chain.links}
    assert "part" not in {lk.name for lk in arm.planning_robot.chain.links}  # detached again
    # and the scene the rest was planned in has the part where GetSTA saw it, in the bin
    end = done.scenes["end"].object("part")
    assert np.allclose(end.pose[:2, 3], PLACE, atol=PLACE_TOLERANCE_M)


def test_a_grip_over_nothing_names_the_move_and_carries_nothing_off(
        arm: Arm, cell: CellSession) -> None:
    cell.wc.abs_move("part", (0.5, 1.5, -0.05))  # on the floor, far from the pick
    moves = pick_and_place(arm.home, tcp_offset(arm.robot))[:3]
    with pytest.raises(GripError) as info:
        run_pick_place(arm, cell, moves)
    err = info.value
    assert err.move == "pick" and err.vacuum == "KR60gripper"
    assert "holds nothing" in err.seen
    assert any("move 2 (pick, LIN)" in n for n in err.__notes__)
    assert arm.attached == ()
    assert "part" not in {lk.name for lk in arm.planning_robot.chain.links}
    assert arm.client is not None
    eff = arm.client.wait_effector("KR60gripper", "OPEN", timeout=3.0)  # opened again
    assert eff.status == "OPEN"


def test_suction_lost_while_carrying_stops_the_arm_and_says_so(
        arm: Arm, cell: CellSession) -> None:
    assert arm.client is not None
    client = arm.client
    moves = pick_and_place(arm.home, tcp_offset(arm.robot))

    def after(i: int, done: MoveResult) -> None:
        if done.move.name == "lift":  # 0.8 s into the transfer, the vacuum lets go
            threading.Timer(0.8, client.set_effector,
                            ("Gripper", "KR60gripper", "OPEN")).start()

    with pytest.raises(ExecutionAbortedError) as info:
        run_pick_place(arm, cell, moves, progress=after)
    assert "suction lost" in str(info.value)
    assert any("(transfer, PTP)" in n for n in info.value.__notes__)
    assert arm.attached == ()  # the planner carries nothing the gripper lost
