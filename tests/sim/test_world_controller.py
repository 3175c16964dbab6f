"""The WorldController over real TCP, as ``WorldController.uc`` and ``BotConnection.uc
ProcessWorldController`` have it: Create, Kill, KillAll, AbsMove, RelMove and GetSTA (its exact,
unclosed reply), and every refusal UDK makes (unknown class, duplicate name, a spawn inside
existing geometry, CONTROL from a robot's connection), with the connection kept."""

from __future__ import annotations

import logging
import re
import time
from collections.abc import Iterator

import numpy as np
import pytest

from usar_arm.core.cell_errors import WorldControllerError
from usar_arm.planning.cell_scene import scene_from_sightings
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_controller import parse_vector
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.world_controller import WorldControllerClient

ON_TABLE = (1.6, 0.5, -0.75)
"""A 0.1 m tall crate's centre resting on the table top (z-down: 0.70 m up)."""
SMALL = (0.4, 0.4, 0.4)


@pytest.fixture()
def server() -> Iterator[SimServer]:
    """A simulator of the default world (the table cell), 3x speed."""
    with SimServer(SimOptions(port=0, speed=3.0)) as s:
        yield s


@pytest.fixture()
def wc(server: SimServer) -> Iterator[WorldControllerClient]:
    """A WorldController connection."""
    with WorldControllerClient(port=server.port, timeout=5.0) as client:
        yield client


def _sta_line(wc: WorldControllerClient, **fields: str) -> str:
    """The raw text of GetSTA's reply."""
    return wc.request(m.Control("GetSTA", **fields), lambda x: isinstance(x, m.WcStatus)).line


def test_create_and_get_sta_in_udks_exact_unclosed_form(wc: WorldControllerClient) -> None:
    wc.create("part", "WCCrate", ON_TABLE, scale=SMALL, memory="tag7")
    line = _sta_line(wc)
    assert re.fullmatch(r"STA \{Name part\} \{Size 0\.1[12]\d\d,0\.1[12]\d\d,0\.(0999|1000)\} "
                        r"\{Location 1\.(5999|6000),0\.(4999|5000),-0\.7(49\d|500) "
                        r"\{Memory \{tag7\} \{Rotation -?0\.000\d,-?0\.000\d,-?0\.000\d\}",
                        line), line
    assert _sta_line(wc, name="PART") == "STA"  # GetSTA's name filter is exact; no object: "STA"
    assert _sta_line(wc, class_name="WCObjectBin") == "STA"
    assert _sta_line(wc, class_name="wccrate").startswith("STA {Name part}")  # a class: any case
    assert _sta_line(wc, class_name="WCObject").startswith("STA {Name part}")  # a superclass
    assert _sta_line(wc, class_name="USARPhysObj.WCCrate") == "STA"  # isA: no package


def test_a_rigid_crate_falls_and_rests_and_a_static_one_stays(wc: WorldControllerClient) -> None:
    wc.create("falling", "WCCrate", (1.6, 0.5, -1.2), scale=SMALL)  # 0.45 m above the table
    wc.create("hanging", "WCCrate", (1.6, -0.5, -1.2), scale=SMALL, physics="None")
    wc.create("absent", "WCCrate", (1.3, 0.6, -1.2), scale=SMALL, physics="")  # no Physics
    time.sleep(1.5)
    sta = wc.get_sta()
    assert sta.find("falling").location[2] == pytest.approx(-0.75, abs=2e-3)  # type: ignore[union-attr]
    assert sta.find("hanging").location[2] == pytest.approx(-1.2, abs=1e-3)  # type: ignore[union-attr]
    assert sta.find("absent").location[2] == pytest.approx(-1.2, abs=1e-3)  # type: ignore[union-attr]


def test_mass_and_size_scale_as_wcobject_init_does(server: SimServer,
                                                   wc: WorldControllerClient) -> None:
    wc.create("big", "WCObjectBin", (0.0, 3.0, -0.2))
    wc.create("small", "WCObjectBin", (0.0, -3.0, -0.1), scale=(0.5, 0.5, 0.5))
    sta = wc.get_sta()
    assert np.allclose(sta.find("big").size, (0.40, 0.30, 0.20), atol=2e-3)  # type: ignore[union-attr]
    assert np.allclose(sta.find("small").size, (0.20, 0.15, 0.10), atol=2e-3)  # type: ignore[union-attr]
    world = server.world  # (the model's masses do not change while it runs)
    masses = {o.name: float(world.model.body_subtreemass[o.body_id])
              for o in world.objects.objects.values()}
    assert masses == pytest.approx({"big": 10.0, "small": 10.0 * 0.125})


def test_kill_and_kill_all_with_and_without_a_box(wc: WorldControllerClient) -> None:
    for name, x in (("a", -2.0), ("b", -3.0), ("c", -4.0)):
        wc.create(name, "WCCrate", (x, 0.0, -0.125))
    wc.create("kept", "WCCrate", (-5.0, 0.0, -0.125), permanent=True)
    wc.kill("A")  # Kill finds a name in any case
    assert [o.name for o in wc.get_sta().objects] == ["b", "c", "kept"]
    # The box is compared in Unreal units (z negated): inside is max.z < z < min.z on the wire.
    wc.kill_all((-3.5, -1.0, 0.0), (-2.5, 1.0, -1.0))
    assert [o.name for o in wc.get_sta().objects] == ["c", "kept"]
    wc.kill_all((-4.5, -1.0, -1.0), (-3.5, 1.0, 0.0))  # z the REP-103 way round: nothing inside
    assert [o.name for o in wc.get_sta().objects] == ["c", "kept"]
    wc.kill_all()
    assert [o.name for o in wc.get_sta().objects] == ["kept"]  # permanent objects stay


def test_abs_move_and_rel_move_an_object_and_a_robot(server: SimServer,
                                                     wc: WorldControllerClient) -> None:
    wc.create("box", "WCCrate", (-2.0, 0.0, -1.0), physics="None")
    wc.abs_move("BOX", (-2.0, 2.0, -1.0), (0.0, 0.0, 0.5))
    moved = wc.get_sta().find("box")
    assert moved is not None and np.allclose(moved.location, (-2.0, 2.0, -1.0), atol=1e-3)
    assert moved.rotation[2] == pytest.approx(0.5, abs=1e-3)
    wc.rel_move("box", (0.5, 0.0, 0.0))
    assert wc.get_sta().find("box").location[0] == pytest.approx(-1.5, abs=1e-3)  # type: ignore[union-attr]
    with UsarClient(port=server.port) as robot:
        robot.spawn("USARBot.KR60", name="mover", location=(0.0, -4.0, 0.0))
        wc.abs_move("mover", (0.0, -6.0, 0.0))
        robot.wait_sen("GroundTruth")
        time.sleep(0.3)
        assert robot.wait_sen("GroundTruth").location == pytest.approx((0.0, -6.0, 0.0),
                                                                       abs=1e-3)


def test_refusals_keep_the_connection(wc: WorldControllerClient, caplog) -> None:
    caplog.set_level(logging.INFO, "usar_arm.sim")
    wc.create("part", "WCCrate", ON_TABLE, scale=SMALL)
    with pytest.raises(WorldControllerError, match="already exists"):
        wc.create("PART", "WCCrate", (0.0, 3.0, -0.2))  # duplicate, without regard to case
    with pytest.raises(WorldControllerError, match="an unknown class"):
        wc.create("x", "WCNoSuchThing", (0.0, 3.0, -0.2), timeout=0.5)
    with pytest.raises(WorldControllerError, match="inside existing geometry"):
        wc.create("y", "WCCrate", (1.6, 0.0, -0.675), timeout=0.5)  # in the table top
    wc.send_line("CONTROL {Type create} {ClassName WCCrate} {Name z} {Location 0,3,-0.2}")
    wc.send_line("CONTROL {Type NoSuch}")
    assert [o.name for o in wc.get_sta().objects] == ["part"]  # Type is compared exactly
    text = caplog.text
    for said in ("already exists", "Invalid class name USARPhysObj.WCNoSuchThing",
                 "inside existing geometry", "Unsupported world controller command create",
                 "Object not fully qualified, assuming USARPhysObj.WCCrate"):
        assert said in text, said


def test_a_malformed_vector_reads_as_udks_parse_vector_and_is_logged(
        wc: WorldControllerClient, caplog) -> None:
    caplog.set_level(logging.INFO, "usar_arm.sim")
    wc.send_line("CONTROL {Type Create} {ClassName WCCrate} {Name v} {Location -3} "
                 "{Physics None}")  # ParseVector("-3") is (0, 0, -3): 3 m up...
    wc.send_line("CONTROL {Type Create} {ClassName WCCrate} {Name w} {Location 2,-3} "
                 "{Physics None}")  # ... and "2,-3" is (2, 0, -3)
    wc.send_line("CONTROL {Type Create} {ClassName WCCrate} {Name u} {Location a,b,-1} "
                 "{Physics None}")  # words read 0: (0, 0, -1)
    sta = wc.get_sta()
    assert sta.find("v").location == pytest.approx((0.0, 0.0, -3.0), abs=1e-3)  # type: ignore[union-attr]
    assert sta.find("w").location == pytest.approx((2.0, 0.0, -3.0), abs=1e-3)  # type: ignore[union-attr]
    assert sta.find("u").location == pytest.approx((0.0, 0.0, -1.0), abs=1e-3)  # type: ignore[union-attr]
    assert caplog.text.count("is not x,y,z") >= 3


def test_control_from_a_robots_connection_is_ignored(server: SimServer, caplog) -> None:
    caplog.set_level(logging.INFO, "usar_arm.sim")
    with UsarClient(port=server.port) as robot, WorldControllerClient(port=server.port) as wc:
        robot.spawn("USARBot.KR60", start="RobotStart1")
        robot.send_line("CONTROL {Type Create} {ClassName WCCrate} {Name r} {Location 0,3,-1}")
        robot.send_line("CONTROL {Type GetSTA}")
        time.sleep(0.3)
        assert wc.get_sta().objects == () and "Bot is not a world controller" in caplog.text
        assert robot.wait_asta("KR60Arm")  # still served


def test_closing_the_world_controller_cleans_up_all_but_the_permanent(
        server: SimServer) -> None:
    with WorldControllerClient(port=server.port) as first:
        first.create("gone", "WCCrate", (0.0, 3.0, -0.125))
        first.create("stays", "WCCrate", (0.0, -3.0, -0.125), permanent=True)
        with WorldControllerClient(port=server.port) as second:
            second.create("theirs", "WCCrate", (0.0, 4.0, -0.125))
    time.sleep(0.3)
    assert [o.name for o in server.world.objects.objects.values()] == ["stays"]


@pytest.mark.parametrize(("text", "vector", "ok"), [
    ("1,2,3", (1.0, 2.0, 3.0), True), ("5", (0.0, 0.0, 5.0), False),
    ("1,2", (1.0, 0.0, 2.0), False), ("1,2,3,4", (1.0, 2.0, 3.0), False),
    ("a,b,c", (0.0, 0.0, 0.0), False), ("1.5x,2,3", (1.5, 2.0, 3.0), False),
    ("", (0.0, 0.0, 0.0), True), (" -1e1, .5 ,3", (-10.0, 0.5, 3.0), True)])
def test_parse_vector_is_utilities_parse_vector(text: str, vector: tuple[float, ...],
                                                ok: bool) -> None:
    assert parse_vector(text) == (vector, ok)


def test_sightings_name_each_objects_class_and_give_the_planners_scene(
        wc: WorldControllerClient) -> None:
    wc.create("crate", "WCCrateRed", (0.0, 3.0, -0.5), scale=(0.5, 1.0, 2.0), physics="None")
    wc.create("tray", "WCKitTray", (0.0, -3.0, -0.5), rotation=(0.0, 0.0, 0.3), physics="None")
    seen = {s.name: s for s in wc.sightings()}
    assert {n: s.wc_class.name for n, s in seen.items()} == {"crate": "WCCrateRed",
                                                             "tray": "WCKitTray"}
    scene = scene_from_sightings(list(seen.values()))
    crate = scene.object("crate")
    assert crate.shape.size == pytest.approx((0.15, 0.30, 0.50), abs=2e-4)  # type: ignore[union-attr]
    assert crate.pose[:3, 3] == pytest.approx((0.0, -3.0, 0.5), abs=2e-4)  # REP-103 base_link
    assert {o.name for o in scene.objects} >= {"tray/floor", "tray/wall_left"}


def test_the_fanucs_tool_changer_starts_empty(server: SimServer) -> None:
    with UsarClient(port=server.port) as robot:
        robot.spawn("USARBot.Fanuc_M16iB20", location=(0.0, -4.0, 0.0))
        eff = robot.wait_effector("toolchanger")
        assert eff.status == "OPEN" and eff.get("Tool") is None
        assert robot.get_conf("ToolChanger").items[0].name == "toolchanger"  # type: ignore[union-attr]
