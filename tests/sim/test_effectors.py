"""The KR60's effectors over real TCP, as UDK has them: ``toolchange`` (a ToolChanger on the
flange) holding ``KR60gripper`` (a VacuumGripper); golden strings from ``Effector.uc``,
``Gripper.uc`` and ``ToolChanger.uc``; SET routing as ``USARVehicle.SetCommand``; the vacuum's
trace, hold, release and suction loss (``Vacuum.uc``); the tool changer's drop and pick-up; and
the GripTruth extension beside EFF."""

from __future__ import annotations

import re
import time
from collections.abc import Iterator

import numpy as np
import pytest

from tests.sim.cell_helpers import changer_pose, drive, ik_down
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import parse_line
from usar_arm.usarsim.contact_watch import ContactWatch
from usar_arm.usarsim.world_controller import WorldControllerClient

PICK = np.array([1.45, 0.45, -0.75])
"""The part's centre on the table (z-down world; the table scene's pick, y flipped)."""
PART_SCALE = (0.4, 0.4, 0.4)
"""A WCCrate scaled to 0.12 x 0.12 x 0.10 m."""


@pytest.fixture()
def cell() -> Iterator[tuple[SimServer, UsarClient]]:
    """A simulator (3x speed) with a KR60 at RobotStart1."""
    server = SimServer(SimOptions(port=0, speed=3.0))
    server.start()
    client = UsarClient(port=server.port, timeout=10.0)
    client.connect()
    client.spawn("USARBot.KR60", start="RobotStart1")
    try:
        yield server, client
    finally:
        client.close()
        server.stop()


def _lines(client: UsarClient, head: str, seconds: float) -> list[str]:
    got: list[str] = []
    unsubscribe = client.subscribe(lambda rec: got.append(rec.line)
                                   if rec.line.startswith(head) else None)
    time.sleep(seconds)
    unsubscribe()
    return got


def _hover_over_part(client: UsarClient, server: SimServer) -> WorldControllerClient:
    """A WorldController with the part on the table, and the arm with its suction zone
    (0.183-0.308 m along the gripper's +z) around the part's top: the gripper 0.25 m above
    the part's top face."""
    wc = WorldControllerClient(port=server.port, timeout=10.0)
    wc.connect()
    wc.create("part", "WCCrate", tuple(PICK), scale=PART_SCALE)
    drive(client, ik_down(PICK - (0.0, 0.0, 0.05 + 0.25)))
    return wc


# ------------------------------------------------------------------ the lines


def test_eff_lines_every_tenth_of_a_simulated_second_as_udk_prints_them(cell) -> None:
    _, client = cell
    lines = _lines(client, "EFF", 1.0)
    changer = [ln for ln in lines if "{Name toolchange}" in ln]
    gripper = [ln for ln in lines if "{Name KR60gripper}" in ln]
    golden = re.compile(r"EFF \{Time (\d+\.\d{4})\} \{Type ToolChanger\} \{Name toolchange\} "
                        r"\{Status CLOSED\}\{ToolType Gripper\} \{Tool KR60gripper\}")
    assert changer and all(golden.fullmatch(ln) for ln in changer), changer[:2]
    assert gripper and all(re.fullmatch(r"EFF \{Time \d+\.\d{4}\} \{Type Gripper\} "
                                        r"\{Name KR60gripper\} \{Status OPEN\}", ln)
                           for ln in gripper), gripper[:2]
    times = [float(golden.fullmatch(ln).group(1)) for ln in changer]  # type: ignore[union-attr]
    assert np.allclose(np.diff(times), 0.1, atol=1e-3), times


def _reply(client: UsarClient, line: str) -> str:
    """The text of the reply to a GETCONF or GETGEO line."""
    return client.request(parse_line(line), lambda x: isinstance(x, (m.Conf, m.Geo))).line


def test_conf_and_geo_of_the_effectors_are_udks_golden_strings(cell) -> None:
    _, client = cell
    replies = [_reply(client, line) for line in (
        "GETCONF {Type Gripper}", "GETCONF {Type toolchanger} {Name TOOLCHANGE}",  # any case
        "GETGEO {Type ToolChanger}", "GETGEO {Type Gripper} {Name KR60gripper}")]
    assert replies[0] == ("CONF {Type Gripper} {Name KR60gripper} {Opcode Grip} {MaxVal 1} "
                          "{MinVal 0} {Opcode Close} {Opcode Open}")
    assert replies[1] == ("CONF {Type toolchanger} {Name toolchange}{PositionTolerance 0.5000} "
                          "{AngleTolerance 0.5000} {Opcode Close} {Opcode Open}")
    # The tool changer: measured from joint 6's anchor (1.625, 0.02, -1.97), 0.065 m beyond it
    # along x at the zero pose (float32: 0.06); the gripper: on the tool changer, no MountLink.
    assert re.fullmatch(r"GEO \{Type ToolChanger\} \{Name toolchange\} \{Location 0\.0[67],"
                        r"-?0\.00,-?0\.0[01]\} \{Orientation -?0\.\d\d,1\.5\d,-?0\.\d\d\}"
                        r"\{Mount KR60Arm\}\{MountLink 6\}\{Tip 0\.00,0\.00,0\.00\}",
                        replies[2]), replies[2]
    assert re.fullmatch(r"GEO \{Type Gripper\} \{Name KR60gripper\} \{Location -?0\.00,-?0\.00,"
                        r"-?0\.00\} \{Orientation -?0\.\d\d,1\.5\d,-?0\.\d\d\}"
                        r"\{Mount toolchange\}\{Tip 0\.00,0\.00,0\.18\}", replies[3]), replies[3]


def test_nothing_answers_a_query_that_matches_no_effector(cell) -> None:
    _, client = cell
    for line in ("GETCONF {Type Gripper} {Name nosuch}", "GETGEO {Type ToolChanger} {Name x}",
                 "GETCONF {Type Effector}"):
        client.send_line(line)
    # The platform's CONF is the first reply after them: they were answered with nothing.
    reply = client.request(m.GetConf("Robot"), lambda x: True)
    assert reply.line.startswith("CONF {Name KR60}"), reply.line


# ------------------------------------------------------------------ SET routing


def test_set_is_routed_by_type_and_name_in_any_case_and_never_answered(cell) -> None:
    _, client = cell
    got: list[str] = []
    client.subscribe(lambda rec: got.append(rec.line) if not rec.line.startswith(
        ("EFF", "SEN", "STA", "ASTA")) else None)
    t0 = client.wait_effector("KR60gripper").time
    client.send_line("SET {Type gripper} {Name kr60GRIPPER} {Opcode close}")
    assert client.wait_effector("KR60gripper", "CLOSED", after_time=t0).status == "CLOSED"
    client.send_line("SET {Type GRIPPER} {Name } {Opcode Open}")  # an empty name: all
    t1 = client.wait_effector("KR60gripper", "OPEN").time
    client.send_line("SET {Type Gripper} {Name KR60gripper} {Opcode GRIP} {Params 1}")
    assert client.wait_effector("KR60gripper", "CLOSED", after_time=t1).status == "CLOSED"
    client.send_line("SET {Type Gripper} {Name other} {Opcode OPEN}")  # matches nothing
    client.send_line("SET {Type Joint} {Name KR60gripper} {Opcode OPEN}")  # Joint: not effectors
    time.sleep(0.3)
    assert client.latest_eff("KR60gripper").status == "CLOSED"  # type: ignore[union-attr]
    assert got == [], got  # no reply to any SET


def test_act_gripper_reaches_the_vacuum(cell) -> None:
    _, client = cell
    t0 = client.wait_effector("KR60gripper", "OPEN").time
    client.send_line("ACT {Name KR60gripper} {Gripper 1}")
    assert client.wait_effector("KR60gripper", "CLOSED", after_time=t0).time > t0
    client.send_line("ACT {Name kr60gripper} {Gripper 0}")
    client.wait_effector("KR60gripper", "OPEN")


# ------------------------------------------------------------------ the vacuum


def test_close_over_nothing_reports_closed_while_nothing_is_held(cell) -> None:
    _, client = cell
    t0 = client.wait_effector("KR60gripper").time
    client.set_effector("Gripper", "KR60gripper", "CLOSE")
    eff = client.wait_effector("KR60gripper", "CLOSED", after_time=t0)
    grip = client.wait_grip("KR60gripper", after_time=eff.time)
    assert (grip.holding, grip.object) == (False, None)
    client.set_effector("Gripper", "KR60gripper", "OPEN")
    eff = client.wait_effector("KR60gripper", "OPEN", after_time=eff.time)
    assert client.wait_grip("KR60gripper", after_time=eff.time).holding is False


def test_a_crate_is_gripped_carried_released_onto_the_table_and_rests(cell) -> None:
    server, client = cell
    with _hover_over_part(client, server) as wc:
        before = wc.get_sta(name="part").objects[0]
        client.set_effector("Gripper", "KR60gripper", "CLOSE")
        eff = client.wait_effector("KR60gripper", "CLOSED")
        grip = client.wait_grip("KR60gripper", after_time=eff.time)
        assert (grip.holding, grip.object) == (True, "part")
        truth = server.truth(client.local_port)
        assert truth is not None and truth.effectors["KR60gripper"].held == "part"
        place = np.array([1.30, 0.60, PICK[2]])  # nearer the arm and its right (REP-103)
        drive(client, ik_down(PICK - (0.0, 0.0, 0.05 + 0.25 + 0.10)))
        lifted = wc.get_sta(name="part").objects[0]
        assert lifted.location[2] < before.location[2] - 0.08  # lifted ~0.1 m (z down)
        drive(client, ik_down(place - (0.0, 0.0, 0.05 + 0.25 + 0.01)))
        carried = wc.get_sta(name="part").objects[0]
        assert np.allclose(carried.location[:2], place[:2], atol=0.01), carried
        client.set_effector("Gripper", "KR60gripper", "OPEN")
        client.wait_effector("KR60gripper", "OPEN")
        time.sleep(1.0)  # it falls the centimetre and comes to rest
        rest = [wc.get_sta(name="part").objects[0] for _ in range(2)]
        assert np.allclose(rest[0].location, rest[1].location, atol=1e-3)
        assert rest[1].location[2] == pytest.approx(PICK[2], abs=2e-3)  # on the table again
        assert np.allclose(rest[1].location[:2], place[:2], atol=0.01)


def test_a_static_object_is_held_and_stays_where_it_is_released(cell) -> None:
    server, client = cell
    drive(client, np.zeros(6))
    tip = changer_pose(np.zeros(6))[:3, 3] + (0.25, 0.0, 0.0)  # 0.25 m out of the flange
    with WorldControllerClient(port=server.port) as wc:
        wc.create("floating", "WCCrate", tuple(tip + np.array([0.05, 0.0, 0.0])), scale=PART_SCALE,
                  physics="None")  # a static crate in the air, its near face in the zone
        client.set_effector("Gripper", "KR60gripper", "CLOSE")
        grip = client.wait_grip("KR60gripper", after_time=client.wait_effector(
            "KR60gripper", "CLOSED").time)
        assert grip.object == "floating"
        drive(client, np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.0]))
        client.set_effector("Gripper", "KR60gripper", "OPEN")
        client.wait_effector("KR60gripper", "OPEN")
        moved = wc.get_sta(name="floating").objects[0]
        time.sleep(0.5)
        assert np.allclose(wc.get_sta(name="floating").objects[0].location, moved.location,
                           atol=1e-3)  # PHYS_None again: it stays in mid-air
        assert np.linalg.norm(np.subtract(moved.location, tip)) > 0.2  # it was carried


def test_suction_is_lost_when_the_held_part_is_driven_into_the_tower(cell) -> None:
    server, client = cell
    with _hover_over_part(client, server) as wc:
        client.set_effector("Gripper", "KR60gripper", "CLOSE")
        client.wait_grip("KR60gripper", after_time=client.wait_effector(
            "KR60gripper", "CLOSED").time)
        # The tool changer 1.52 m up: the gripper's body (0.181 m long) clears the tower's
        # top (1.30 m) and the part, 0.25-0.35 m below the tool changer, does not.
        lifted = ik_down(np.array([PICK[0], PICK[1], -1.52]))
        drive(client, lifted)
        with ContactWatch(client.subscribe, "KR60") as watch:
            swing = lifted + np.array([0.6, 0, 0, 0, 0, 0])  # about the base: into the tower
            client.act("KR60Arm", [float(v) for v in swing])
            eff = client.wait_effector("KR60gripper", "OPEN", timeout=10.0)  # no command
            assert client.wait_grip("KR60gripper", after_time=eff.time).holding is False
            assert any({p.a, p.b} == {"object:part", "scenery:tower"} for p in watch.pairs())
        assert wc.get_sta(name="part").objects  # dropped, not destroyed


# ------------------------------------------------------------------ the tool changer


def test_tool_changer_drops_the_gripper_and_picks_it_up_only_within_tolerance(cell) -> None:
    server, client = cell
    above = PICK.copy()
    above[2] = -0.70 - 0.183 - 0.02  # the gripper's tip 2 cm above the table
    q_above = ik_down(above)
    drive(client, q_above)
    client.set_effector("ToolChanger", "toolchange", "OPEN")
    eff = client.wait_effector("toolchange", "OPEN")
    time.sleep(1.0)  # it falls 2 cm onto its tip and stands
    assert client.latest_eff("toolchange").status == "OPEN"  # type: ignore[union-attr]
    gone = _lines(client, "EFF", 0.5)
    assert gone and not [ln for ln in gone if "KR60gripper" in ln]  # a dropped tool is silent
    truth = server.truth(client.local_port)
    assert truth is not None and truth.effectors["KR60gripper"].attached is False
    client.send_line("SET {Type Gripper} {Name KR60gripper} {Opcode CLOSE}")  # not a part now
    # 0.6 m above it: the ray (1.0 m) hits the tool, but it is beyond the 0.5 m tolerance.
    drive(client, ik_down(above - (0.0, 0.0, 0.6), near=q_above))
    client.set_effector("ToolChanger", "toolchange", "CLOSE")
    time.sleep(0.5)
    assert client.wait_effector("toolchange", after_time=eff.time).status == "OPEN"
    drive(client, ik_down(above - (0.0, 0.0, 0.1), near=q_above))
    client.set_effector("ToolChanger", "toolchange", "CLOSE")
    closed = client.wait_effector("toolchange", "CLOSED")
    assert closed.get("Tool") == "KR60gripper" and closed.get("ToolType") == "Gripper"
    assert client.wait_effector("KR60gripper").status == "OPEN"  # it talks again
    truth = server.truth(client.local_port)
    assert truth is not None and truth.effectors["KR60gripper"].attached is True


def test_close_while_holding_and_open_while_empty_change_nothing(cell) -> None:
    _, client = cell
    client.set_effector("ToolChanger", "toolchange", "CLOSE")
    eff = client.wait_effector("toolchange")
    time.sleep(0.3)
    assert client.wait_effector("toolchange", after_time=eff.time).get("Tool") == "KR60gripper"
    client.set_effector("ToolChanger", "toolchange", "OPEN")
    client.wait_effector("toolchange", "OPEN")
    client.set_effector("ToolChanger", "toolchange", "OPEN")  # empty: nothing happens
    time.sleep(0.3)
    assert client.latest_eff("toolchange").status == "OPEN"  # type: ignore[union-attr]


def test_the_held_tool_and_object_do_not_load_the_arm(cell) -> None:
    """The tool rides on its carrier and the object on the tool: the arm's joints settle
    where they do without a tool: the joints of two arms, one holding the gripper and a crate,
    one without a tool, agree to 1e-5 rad (welded to the flange, the 1.8 kg would sag joint 2
    by about 20 mrad)."""
    server, client = cell
    other = UsarClient(port=server.port, timeout=10.0)
    other.connect()
    other.spawn("USARBot.KR60", location=(0.0, 6.0, 0.0), name="bare")
    other.set_effector("ToolChanger", "toolchange", "OPEN")
    with _hover_over_part(client, server):
        client.set_effector("Gripper", "KR60gripper", "CLOSE")
        client.wait_grip("KR60gripper", after_time=client.wait_effector(
            "KR60gripper", "CLOSED").time)
        q = ik_down(PICK - (0.0, 0.0, 0.05 + 0.25 + 0.15))
        drive(client, q)
        drive(other, q)
        time.sleep(2.0)  # settled (to well below 1e-5 rad)
        held = server.truth(client.local_port)
        bare = server.truth(other.local_port)
        assert held is not None and bare is not None
        assert held.effectors["KR60gripper"].held == "part"
        assert not bare.effectors["KR60gripper"].attached
        assert np.allclose(held.joints["KR60Arm"], bare.joints["KR60Arm"], atol=1e-5)
    other.close()
