"""What a spawned robot says about itself: CONF and GEO replies, computed as UDK computes them.

With the ``udk`` wire precision, an actuator link's GEO Location is computed the way
``Actuator.uc GetGeoData`` does it, in 32-bit floats and Unreal units (``MeterVectorToUU`` of each
joint offset, the difference to the parent's, ``LengthVectorFromUU``), then printed by
``FloatString(p=3)``; this reproduces UDK's numbers (docs/protocol.md section 7), e.g. the KR60's
``-1.004``. With the ``full`` precision the exact float64 difference is sent.
"""

from __future__ import annotations

import numpy as np

from usar_arm.core.spatial import matrix_to_rpy, rpy_to_matrix
from usar_arm.sim.robot_spec import ActuatorSpec, RobotSpec
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import NumberStyle

METER_TO_UU = 250.0
"""Unreal units per metre (``C_MeterToUU``)."""
SCAN_INTERVAL = 0.1
"""Seconds between status/sensor messages (``ScanInterval``, ``StatusTimer``)."""


def _udk_offset_difference(child: m.Vector3, parent: m.Vector3 | None) -> m.Vector3:
    """``LengthVectorFromUU(MeterVectorToUU(child) - MeterVectorToUU(parent))`` in float32."""
    f32 = np.float32
    scale = f32(METER_TO_UU)

    def to_uu(v: m.Vector3) -> list[np.float32]:
        out = [f32(f32(c) * scale) for c in v]
        out[2] = f32(-out[2])  # RightHand: negate z
        return out

    uu = to_uu(child)
    if parent is not None:
        pu = to_uu(parent)
        uu = [f32(a - b) for a, b in zip(uu, pu, strict=True)]
    res = [f32(c / scale) for c in uu]
    res[2] = f32(-res[2])
    return (float(res[0]), float(res[1]), float(res[2]))


def link_geometry(act: ActuatorSpec, style: NumberStyle) -> tuple[m.LinkGeo, ...]:
    """The per-link GEO groups of an actuator."""
    links = []
    for i, jt in enumerate(act.joints):
        p = act.parent_index(i)
        parent = act.joints[p] if p >= 0 else None
        if style.name == "udk":
            loc = _udk_offset_difference(jt.offset, parent.offset if parent else None)
        else:
            base = np.zeros(3) if parent is None else np.asarray(parent.offset)
            d = np.asarray(jt.offset) - base
            loc = (float(d[0]), float(d[1]), float(d[2]))
        rot = rpy_to_matrix(jt.direction)
        if parent is not None:
            rot = rpy_to_matrix(parent.direction).T @ rot
        links.append(m.LinkGeo(i + 1, p + 1, loc, matrix_to_rpy(rot)))
    return tuple(links)


def actuator_geo(act: ActuatorSpec, platform_class: str, style: NumberStyle) -> m.GeoItem:
    """GEO item of an actuator mounted on the platform."""
    return m.GeoItem(name=act.name, location=act.position, orientation=act.direction,
                     mount=platform_class, links=link_geometry(act, style), tip=act.tip_offset)


def actuator_conf(act: ActuatorSpec) -> m.ConfItem:
    """CONF item of an actuator: joint type, MaxTorque and limits per link (no speeds, as UDK)."""
    return m.ConfItem(act.name, links=tuple(
        m.LinkConf(i + 1, jt.type, max_torque=jt.max_force, min_value=jt.limit_low,
                   max_value=jt.limit_high) for i, jt in enumerate(act.joints)))


def tip_sensor_geo(act: ActuatorSpec) -> m.GeoItem:
    """GEO of the tip GroundTruth sensor (an extension): mounted on the last link.

    Location is the sensor's offset from that link's joint anchor in the actuator frame (the
    tip offset), Orientation its rotation relative to that joint's frame, the same conventions
    as the actuator's link GEO.
    """
    last = act.joints[-1]
    rel = rpy_to_matrix(last.direction).T  # sensor frame = actuator frame at the zero pose
    return m.GeoItem(name=str(act.tip_sensor), location=act.tip_offset,
                     orientation=matrix_to_rpy(rel), mount=act.name,
                     mount_link=len(act.joints))


def conf_reply(spec: RobotSpec, robot_name: str, type_: str, name: str | None
               ) -> m.Conf | m.PlatformConf | None:
    """The CONF line answering ``GETCONF {Type type_} [{Name name}]``, or None (no reply)."""
    if type_ == "Robot":
        return m.PlatformConf(robot_name, spec.platform_type,
                              (("SteeringType", spec.steering_type),
                               ("Mass", f"{spec.platform_mass:g}")))
    items: list[m.ConfItem] = []
    if type_.lower() == "actuator":
        items = [actuator_conf(a) for a in spec.actuators if _matches(a.name, name)]
    elif type_.lower() == "groundtruth":
        interval = (("ScanInterval", f"{SCAN_INTERVAL:.4f}"),)
        items = [m.ConfItem(it.name, interval) for it in spec.items
                 if it.type.lower() == "groundtruth" and _matches(it.name, name)]
        items += [m.ConfItem(str(a.tip_sensor), interval) for a in spec.actuators
                  if a.tip_sensor and _matches(a.tip_sensor, name)]
    return m.Conf(type_, tuple(items)) if items else None


def geo_reply(spec: RobotSpec, robot_name: str, type_: str, name: str | None,
              style: NumberStyle) -> m.Geo | None:
    """The GEO line answering ``GETGEO {Type type_} [{Name name}]``, or None (no reply)."""
    if type_ == "Robot":
        return m.Geo(spec.platform_type, (m.GeoItem(robot_name),))
    items: list[m.GeoItem] = []
    if type_.lower() == "actuator":
        items = [actuator_geo(a, spec.short_name, style) for a in spec.actuators
                 if _matches(a.name, name)]
    elif type_.lower() == "groundtruth":
        items = [m.GeoItem(it.name, it.position, it.direction, mount=spec.short_name)
                 for it in spec.items
                 if it.type.lower() == "groundtruth" and _matches(it.name, name)]
        items += [tip_sensor_geo(a) for a in spec.actuators
                  if a.tip_sensor and _matches(a.tip_sensor, name)]
    return m.Geo(type_, tuple(items)) if items else None


def _matches(item_name: str, wanted: str | None) -> bool:
    return wanted is None or wanted == "" or item_name.upper() == wanted.upper()


def known_components(spec: RobotSpec) -> list[str]:
    """``Type Name`` of every component, for log messages."""
    out = [f"Actuator {a.name}" for a in spec.actuators]
    out += [f"{it.type} {it.name}" for it in spec.items]
    out += [f"GroundTruth {a.tip_sensor}" for a in spec.actuators if a.tip_sensor]
    if spec.vehicle is not None:
        out += [f"{s.type} {s.name}" for s in spec.vehicle.sensors]
    return out
