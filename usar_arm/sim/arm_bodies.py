"""An arm's bodies in the simulator's world: one body per part, a position drive per joint
(stiffness = MaxForce, damping = Damping, force limit = MaxForce, as UDK's PhysX drive), the
part's ``.uc`` mass on capsules between the joint anchors, and its collision capsules.

Links collide with the scenery, the WorldController's objects, dropped tools, and the arm's own
links and tool except across a joint, as UDK's joint constraints disable collision between the
two parts they join (:mod:`.scenery` says which bits do what): the arm's own pairs are explicit
MuJoCo contact pairs, all but those across a joint (MuJoCo's own parent filter, which would also
drop the first moving link's contacts with everything welded to the world, is off: see
:func:`usar_arm.sim.mj.new_spec`). The mass capsules touch nothing and the collision
capsules weigh nothing, so contacts add no mass: an arm moves exactly as it did before it could
touch anything.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.core.spatial import Array, invert, transform
from usar_arm.sim import mj
from usar_arm.sim.effector_spec import ToolChangerSpec
from usar_arm.sim.physics_index import ActuatorIndex
from usar_arm.sim.robot_spec import ActuatorSpec, PartSpec
from usar_arm.sim.scenery import LINK_AFFINITY, LINK_BIT, quat

LINK_RADIUS = 0.05
"""Radius (m) of the capsules that carry each part's mass."""


def part_body(prefix: str, part: str) -> str:
    """The MuJoCo body of an arm part: ``<robot key>/<actuator>/<part>``."""
    return f"{prefix}/{part}"


def collision_geom(body: str, i: int) -> str:
    """The name of a body's ``i``-th collision geom."""
    return f"{body}/collision/{i}"


def self_pairs(act: ActuatorSpec) -> list[tuple[str, str]]:
    """The part pairs of an arm that may touch: every two parts with collision geometry that
    no joint joins."""
    joined = {frozenset((jt.parent, jt.child)) for jt in act.joints}
    solid = [p.name for p in act.parts if p.collision]
    return [(a, b) for i, a in enumerate(solid) for b in solid[i + 1:]
            if frozenset((a, b)) not in joined]


def add_pairs(spec: mj.Spec, geoms1: Sequence[str], geoms2: Sequence[str]) -> None:
    """Explicit contact pairs between every geom of ``geoms1`` and every geom of ``geoms2``."""
    for g1 in geoms1:
        for g2 in geoms2:
            spec.add_pair(geomname1=g1, geomname2=g2)


def part_geoms(prefix: str, part: PartSpec) -> list[str]:
    """The collision geoms of an arm part."""
    return [collision_geom(part_body(prefix, part.name), i) for i in range(len(part.collision))]


def add_arm(spec: mj.Spec, platform: mj.Body, key: str, act: ActuatorSpec,
            changers: Sequence[ToolChangerSpec] = ()) -> ActuatorIndex:
    """Add an arm on ``platform``; ``changers`` are the tool changers riding on its parts (a
    site each, ``<key>/<actuator>/<changer>``, where the tool changer's frame is)."""
    prefix = f"{key}/{act.name}"
    mount = act.mount()
    bodies = {act.body: platform.add_body(name=part_body(prefix, act.body),
                                          pos=mount[:3, 3].tolist(), quat=quat(mount[:3, :3]))}
    zero = {act.body: np.eye(4)}
    children: dict[str, list[Array]] = {p.name: [] for p in act.parts}
    joint_names, actuator_names, signs = [], [], []
    for jt in act.joints:
        f0 = jt.frame()
        rel = invert(zero[jt.parent]) @ f0
        children[jt.parent].append(rel[:3, 3])
        body = bodies[jt.parent].add_body(name=part_body(prefix, jt.child),
                                          pos=rel[:3, 3].tolist(), quat=quat(rel[:3, :3]))
        sign = -1.0 if jt.inverse_measure_angle else 1.0
        lo, hi = sorted((sign * jt.limit_low, sign * jt.limit_high))
        jname = f"{prefix}/{jt.name}"
        body.add_joint(name=jname, type=mj.HINGE if jt.revolute else mj.SLIDE,
                       axis=[0.0, 0.0, sign], range=[lo, hi], limited=True)
        drive = spec.add_actuator(name=f"{jname}/drive", target=jname, trntype=mj.TRN_JOINT)
        drive.set_to_position(kp=jt.max_force, kv=jt.damping)
        drive.forcelimited = True
        drive.forcerange = [-jt.max_force, jt.max_force]
        drive.ctrllimited = True
        drive.ctrlrange = [lo, hi]
        bodies[jt.child] = body
        zero[jt.child] = f0
        joint_names.append(jname)
        actuator_names.append(f"{jname}/drive")
        signs.append(sign)
    last = act.joints[-1]
    tip_rel = invert(last.frame()) @ transform(
        pos=np.asarray(last.offset) + np.asarray(act.tip_offset))
    children[last.child].append(tip_rel[:3, 3])
    for part in act.parts:
        _add_mass(bodies[part.name], part.mass, children[part.name])
        _add_collision(bodies[part.name], part, zero[part.name], part_body(prefix, part.name))
    parts = {p.name: p for p in act.parts}
    for a, b in self_pairs(act):
        add_pairs(spec, part_geoms(prefix, parts[a]), part_geoms(prefix, parts[b]))
    tip_site = f"{prefix}/tip"
    bodies[last.child].add_site(name=tip_site, pos=tip_rel[:3, 3].tolist(),
                                quat=quat(tip_rel[:3, :3]))
    sites = {}
    for changer in changers:
        rel = invert(zero[changer.parent]) @ changer.frame()
        sites[changer.name] = f"{prefix}/{changer.name}"
        bodies[changer.parent].add_site(name=sites[changer.name], pos=rel[:3, 3].tolist(),
                                        quat=quat(rel[:3, :3]))
    return ActuatorIndex(act, joint_names, actuator_names, np.array(signs), tip_site=tip_site,
                         changer_sites=sites)


def _add_mass(body: mj.Body, mass: float, ends: list[Array]) -> None:
    """Spread a part's mass over capsules from its frame origin to the next anchors."""
    segments = [e for e in ends if np.linalg.norm(e) > 1e-6]
    if not segments:
        body.add_geom(type=mj.SPHERE, size=[LINK_RADIUS, 0, 0], mass=max(mass, 1e-3),
                      contype=0, conaffinity=0, group=mj.MASS_GROUP)
        return
    for end in segments:
        body.add_geom(type=mj.CAPSULE, size=[LINK_RADIUS, 0, 0],
                      fromto=[0.0, 0.0, 0.0, *end.tolist()],
                      mass=max(mass, 1e-3) / len(segments), contype=0, conaffinity=0,
                      group=mj.MASS_GROUP)


def _add_collision(body: mj.Body, part: PartSpec, frame: Array, name: str) -> None:
    """The part's collision capsules (given in the actuator frame at the zero pose), massless;
    one whose two ends coincide is a sphere."""
    to_part = invert(frame)
    for i, cap in enumerate(part.collision):
        a = (to_part @ np.array([*cap.start, 1.0]))[:3]
        b = (to_part @ np.array([*cap.end, 1.0]))[:3]
        common = {"name": collision_geom(name, i), "mass": 0.0, "contype": LINK_BIT,
                  "conaffinity": LINK_AFFINITY}
        if np.linalg.norm(b - a) < 1e-9:
            body.add_geom(type=mj.SPHERE, size=[cap.radius, 0, 0], pos=a.tolist(), **common)
        else:
            body.add_geom(type=mj.CAPSULE, size=[cap.radius, 0, 0],
                          fromto=[*a.tolist(), *b.tolist()], **common)
