"""Contacts as truth (an extension; UDK reports none): the arm driven into the table is
stopped by it and the contact is reported with its bodies, times and depth, over TCP and
in-process; an arm moving in free space reports none; the first moving link (a child of the
world-welded base, whose contacts MuJoCo's parent filter would drop) touches the scenery; and a
contact lasting one physics step between two reports is never lost."""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from usar_arm.core.spatial import transform
from usar_arm.core.wc_classes import WC_CLASSES
from usar_arm.core.world_file import SceneryBox
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import builtin_robots
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_objects import WcObject
from usar_arm.sim.world_spec import load_world
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.contact_watch import ContactWatch

KR60 = builtin_robots()["USARBot.KR60"]
INTO_THE_TABLE = [0.35, -0.9, 0.0, 0.0, 0.0, 0.0]
"""Shoulder down over the table's right half: link 6 (part Joint6) meets the table top."""


def test_the_arm_driven_into_the_table_is_stopped_and_the_contact_reported() -> None:
    with SimServer(SimOptions(port=0, speed=3.0)) as server, \
            UsarClient(port=server.port, timeout=10.0) as client:
        client.spawn("USARBot.KR60", start="RobotStart1")
        with ContactWatch(client.subscribe, "KR60") as watch:
            start = client.wait_asta("KR60Arm").time
            lines: list[str] = []
            client.subscribe(lambda rec: lines.append(rec.line)
                             if "{Type Contact}" in rec.line else None)
            client.act("KR60Arm", INTO_THE_TABLE)
            time.sleep(2.0)
            end = client.wait_asta("KR60Arm").time
        pairs = [p for p in watch.pairs() if {p.a, p.b} == {"link:KR60/Joint6",
                                                           "scenery:table_top"}]
        assert pairs, watch.pairs()
        assert all(start < p.first <= p.last < end and 0.0 < p.depth < 0.05 for p in pairs)
        assert sum(p.steps for p in pairs) > 100  # it rests on the table
        q = client.wait_asta("KR60Arm").positions()
        assert q[1] > INTO_THE_TABLE[1] + 0.005  # the table holds the shoulder up
        truth = server.truth(client.local_port)
        assert truth is not None and any(
            {p.a, p.b} == {"link:KR60/Joint6", "scenery:table_top"} for p in truth.contacts)
        golden = re.compile(r"SEN \{Time \d+\.\d{4}\} \{Type Contact\} \{Name KR60\} \{Count "
                            r"(\d+)\}( \{Pair \S+ \S+\} \{First \d+\.\d{4}\} \{Last \d+\.\d{4}\}"
                            r" \{Depth \d+\.\d{4}\} \{Steps \d+\})*")
        assert lines and all(golden.fullmatch(ln) for ln in lines), lines[:3]


def test_an_arm_moving_in_free_space_touches_nothing() -> None:
    with SimServer(SimOptions(port=0, speed=3.0)) as server, \
            UsarClient(port=server.port, timeout=10.0) as client:
        client.spawn("USARBot.KR60", start="RobotStart1")
        with ContactWatch(client.subscribe, "KR60") as watch:
            client.act("KR60Arm", [-1.2, 0.2, 0.3, 1.0, 0.5, 2.0])  # above the table, away
            time.sleep(2.0)
            client.act("KR60Arm", [0.0] * 6)
            time.sleep(1.5)
        assert watch.reports >= 10 and watch.pairs() == ()
        truth = server.truth(client.local_port)
        assert truth is not None and truth.contacts == ()


def test_the_first_moving_link_touches_the_scenery() -> None:
    """Joint2 (the shoulder) is a child of the world-welded base: with MuJoCo's parent filter
    on, it would touch nothing welded to the world."""
    posts = [SceneryBox(f"post{i}", (0.07, y, -0.6), (0.05, 0.05, 0.6))
             for i, y in enumerate((0.33, -0.31))]  # 0.32 m from joint 1's axis, either side
    world = PhysicsWorld(scenery=posts)
    world.add_robot("c1", KR60, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    world.set_targets("c1", "KR60Arm", [2.5, 0.0, 0.0, 0.0, 0.0, 0.0])  # swing into a post
    world.step(3000)
    names = {(p.a, p.b) for p in world.contacts.take("c1")}
    assert names & {("link:KR60/Joint2", "scenery:post0"),
                    ("link:KR60/Joint2", "scenery:post1")}, names
    assert world.joint_values("c1", "KR60Arm")[0] < 2.3  # the post stopped it


def test_a_one_step_contact_between_two_reports_is_kept() -> None:
    world = PhysicsWorld(gravity=False)
    world.add_robot("c1", KR60, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    world.step(10)
    world.contacts.take("c1")
    away, into = transform(pos=(0.0, 5.0, -1.0)), transform(pos=(0.49, -0.17, -1.3))
    box = WcObject(world.objects.new_uid(), "blip", "wc", WC_CLASSES["WCCrate"],
                   (0.4, 0.4, 0.4), "None", False, "", "", away)
    world.add_object(box)
    world.step(40)
    world.move_object(box, into)  # into the upper arm (part Joint3) for one step
    world.step(1)
    world.move_object(box, away)
    world.step(59)
    pairs = [p for p in world.contacts.take("c1") if "object:blip" in (p.a, p.b)]
    assert len(pairs) == 1 and pairs[0].steps == 1 and pairs[0].first == pairs[0].last, pairs
    assert pairs[0].depth > 0.01 and "link:KR60/Joint3" in (pairs[0].a, pairs[0].b)
    assert world.contacts.take("c1") == ()  # reported once


@pytest.mark.parametrize("cell", [True, False])
def test_objects_resting_on_the_scenery_are_not_robot_contacts(cell: bool) -> None:
    spec = load_world()
    world = PhysicsWorld(cell=spec.cell if cell else ())
    world.add_robot("c1", KR60, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    crate = WcObject(world.objects.new_uid(), "rest", "wc", WC_CLASSES["WCCrate"],
                     (0.4, 0.4, 0.4), "RigidBody", False, "", "",
                     transform(pos=(1.6, 0.5, -0.76) if cell else (1.6, 0.5, -0.06)))
    world.add_object(crate)
    world.step(500)
    assert world.contacts.take("c1") == ()
    assert np.isclose(world.object_pose(crate)[2, 3], -0.75 if cell else -0.05, atol=2e-3)
