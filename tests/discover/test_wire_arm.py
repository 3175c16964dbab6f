"""Building an arm from CONF/GEO: chains, resolutions, snapping, frames."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.core.errors import DescriptionError
from usar_arm.discover.frames import accumulate, to_frame
from usar_arm.discover.wire_arm import arm_from_replies, printed_resolution, serial_order
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.codec import parse_line

PLATFORM = m.PlatformConf("R", "StaticPlatform")


def test_serial_order_follows_parents_in_any_listing_order() -> None:
    assert serial_order({1: 0, 2: 1, 3: 2}) == [1, 2, 3]
    assert serial_order({3: 2, 1: 0, 2: 1}) == [1, 2, 3]


@pytest.mark.parametrize(("parents", "words"), [
    ({1: 0, 2: 0}, "exactly one link with Parent 0"),
    ({1: 0, 2: 1, 3: 1}, "branching tree"),
    ({1: 0, 2: 5}, "not a link"),
    ({1: 0, 2: 3, 3: 2}, "not connected"),
    ({1: 1}, "its own parent"),
])
def test_parents_that_do_not_form_a_chain_are_rejected(parents: dict, words: str) -> None:
    with pytest.raises(DescriptionError) as info:
        serial_order(parents)
    assert words in str(info.value)


def test_conf_and_geo_must_describe_the_same_links() -> None:
    conf = parse_line("CONF {Type Actuator} {Name A} {Link 1} {JointType Revolute} "
                      "{MinValue -1} {MaxValue 1} {Link 2} {JointType Revolute} {MinValue 1} "
                      "{MaxValue -1}")
    geo = parse_line("GEO {Type Actuator} {Name A} {Link 1} {Parent 0} {Location 0,0,0} "
                     "{Orientation 0,0,0}")
    with pytest.raises(DescriptionError) as info:
        arm_from_replies(PLATFORM, conf.items[0], geo.items[0], [])  # type: ignore[union-attr]
    assert "links [1, 2]" in str(info.value) and "[1]" in str(info.value)


@pytest.mark.parametrize(("where", "bad"), [
    ("conf", m.LinkConf(1, "Revolute", 10.0, -float("inf"), float("inf"))),
    ("conf", m.LinkConf(1, "Revolute", float("nan"), -1.0, 1.0)),
    ("geo", m.LinkGeo(1, 0, (0.1, float("nan"), 0.0), (0.0, 0.0, 0.0))),
    ("tip", (float("inf"), 0.0, 0.0)),
])
def test_numbers_that_are_not_finite_are_rejected_by_name(where: str, bad: object) -> None:
    """Even when a parser lets NaN or inf through, no description is built from them."""
    conf = m.ConfItem("A", (), (bad if where == "conf" else  # type: ignore[arg-type]
                                m.LinkConf(1, "Revolute", 10.0, -1.0, 1.0),))
    link = bad if where == "geo" else m.LinkGeo(1, 0, (0.1, 0.0, 0.0), (0.0, 0.0, 0.0))
    geo = m.GeoItem("A", links=(link,),  # type: ignore[arg-type]
                    tip=bad if where == "tip" else None)  # type: ignore[arg-type]
    with pytest.raises(DescriptionError) as info:
        arm_from_replies(PLATFORM, conf, geo, [])
    assert "expected finite numbers" in str(info.value)
    assert ("nan" in str(info.value)) or ("inf" in str(info.value))


def test_printed_resolution_reads_the_decimals_sent() -> None:
    line = "GEO {Link 1} {Parent 0} {Location 0.070,0.010,-0.413} {Orientation 3.14,0.00,0.00}"
    assert printed_resolution(line, "Location") == pytest.approx(0.001)
    assert printed_resolution(line, "Orientation") == pytest.approx(0.01)
    assert printed_resolution("{Location 0.07000000000000001,0,0}", "Location") == 0.0


def _arm(orientation: str, mount_rpy: str = "0,0,0") -> object:
    conf = parse_line("CONF {Type Actuator} {Name A} {Link 1} {JointType Revolute} "
                      "{MaxTorque 10} {MinValue -1} {MaxValue 1} {Link 2} {JointType Prismatic} "
                      "{MaxTorque 5} {MinValue 0} {MaxValue 0.5}")
    geo = parse_line(f"GEO {{Type Actuator}} {{Name A}} {{Location 0.5,0,-0.1}} "
                     f"{{Orientation {mount_rpy}}}{{Mount R}} {{Link 1}} {{Parent 0}} "
                     f"{{Location 0.1,0,-0.2}} {{Orientation {orientation}}} {{Link 2}} "
                     "{Parent 1} {Location 0.3,0,0} {Orientation 0.00,1.57,0.00}{Tip 0.1,0,0}")
    return arm_from_replies(PLATFORM, conf.items[0], geo.items[0], [], format_geo(geo))


def format_geo(geo: m.Message) -> str:
    from usar_arm.usarsim.codec import format_message
    from usar_arm.usarsim.numbers import UDK
    return format_message(geo, UDK)


def test_frames_within_rounding_of_canonical_are_snapped_and_reported() -> None:
    arm = _arm("3.14,0.00,0.00")
    frames = accumulate(arm)
    assert np.allclose(frames.axes[0], (0, 0, -1), atol=1e-12)
    assert [s.what for s in frames.snaps] == ["link 1 frame", "link 2 frame"]
    # A frame tilted 0.2 rad is kept as sent.
    tilted = accumulate(_arm("0.20,0.00,0.00"))
    assert abs(tilted.axes[0][1] + np.sin(0.2)) < 1e-9


def test_z_up_conversion_flips_y_and_z() -> None:
    frames = to_frame(accumulate(_arm("3.14,0.00,0.00")), "z-up")
    assert np.allclose(frames.anchors[0], (0.1, 0, 0.2))
    assert np.allclose(frames.axes[0], (0, 0, 1))
    assert np.allclose(frames.mount[:3, 3], (0.5, 0, 0.1))
