"""Cut the serial chain to plan out of a URDF's tree: the planning group (an SRDF group, or a
base and tip link, or the whole tree when it is one path), every other movable joint held at a
value (0, or the middle of its limits when 0 is outside them; a mimic joint follows its
leader's held value) and turned into a fixed joint there, and the REP-199 roles pointed at the
group's base and tip. Lengths m, angles rad."""

from __future__ import annotations

from dataclasses import dataclass, replace

from usar_arm.core.errors import RobotStructureError
from usar_arm.core.model import Joint, JointType, KinematicChain, Origin
from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.urdf.description_reader import UrdfTree
from usar_arm.urdf.srdf_reader import Srdf


@dataclass(frozen=True)
class GroupChoice:
    """What the user asked for (all optional): an SRDF group, a base link, a tip link (the
    tool frame that poses refer to)."""

    group: str | None = None
    base: str | None = None
    tip: str | None = None


@dataclass(frozen=True)
class PlanningChain:
    """The chain to plan and how it was cut.

    Attributes:
        chain: the tree with only the group's joints movable. group: the SRDF group's name
            (None without one). base, tip: links. held: joint -> value (rad or m) of each joint
            fixed outside the group. notes: what was decided, for the log.
    """

    chain: KinematicChain
    group: str | None
    base: str
    tip: str
    held: dict[str, float]
    notes: tuple[str, ...]


def _check_tree(chain: KinematicChain, where: str) -> None:
    """One root, no link with two parents (a closed loop)."""
    parents: dict[str, str] = {}
    for j in chain.joints:
        if j.child in parents:
            raise RobotStructureError(f"a closed loop: link {j.child} is the child of joints "
                                      f"{parents[j.child]} and {j.name}", where,
                                      "a tree (each link the child of one joint)")
        parents[j.child] = j.name
    try:
        chain.root  # noqa: B018 - raises on several roots
    except ValueError as exc:
        raise RobotStructureError(str(exc), where, "one connected tree") from None


def _below(chain: KinematicChain, link: str) -> list[Joint]:
    return [j for j in chain.joints if j.parent == link]


def _default_tip(chain: KinematicChain, last: Joint, movable: set[str]) -> str:
    """tool0 when it lies below the last joint; else the last joint's child, followed down
    fixed joints while there is exactly one."""
    if any(lk.name == "tool0" for lk in chain.links) and last in chain.path_to("tool0"):
        return "tool0"
    tip = last.child
    while True:
        fixed = [j for j in _below(chain, tip) if j.name not in movable
                 and j.type is JointType.FIXED]
        if len(fixed) != 1:
            return tip
        tip = fixed[0].child


def _path(chain: KinematicChain, base: str, tip: str, where: str) -> list[Joint]:
    for name in (base, tip):
        if not any(lk.name == name for lk in chain.links):
            raise RobotStructureError(f"no link '{name}'", where,
                                      f"one of {', '.join(lk.name for lk in chain.links)}")
    to_tip, to_base = chain.path_to(tip), chain.path_to(base)
    if to_tip[:len(to_base)] != to_base:
        raise RobotStructureError(f"tip {tip} is not below base {base}", where,
                                  "a tip link downstream of the base link")
    return to_tip[len(to_base):]


def _whole_tree(tree: UrdfTree, where: str) -> list[Joint]:
    """The movable, non-mimic joints when they lie on one path from the root."""
    chain = tree.chain
    own = [j for j in chain.actuated_joints if j.name not in tree.mimic]
    if not own:
        raise RobotStructureError("no movable joint", where, "a chain with at least one joint")
    deepest = max(own, key=lambda j: len(chain.path_to(j.child)))
    path = chain.path_to(deepest.child)
    off = [j.name for j in chain.actuated_joints if j not in path]
    if off:
        raise RobotStructureError(
            f"a branched robot without a planning group (joints {', '.join(off)} are not on "
            f"the path to {deepest.child})", where,
            "an SRDF group (--srdf, --group) or --base-link and --tip-link")
    return own


def cut_chain(tree: UrdfTree, srdf: Srdf | None, choice: GroupChoice, where: str
              ) -> PlanningChain:
    """The planning chain of ``tree`` for ``choice`` (see the module)."""
    chain = tree.chain
    _check_tree(chain, where)
    notes: list[str] = []
    group_name, planned = None, None
    base, tip = choice.base, choice.tip
    if choice.group is not None or (base is None and srdf is not None and srdf.groups):
        if srdf is None:
            raise RobotStructureError(f"group '{choice.group}' asked for without an SRDF",
                                      where, "--srdf FILE with that group")
        spec = (srdf.group(choice.group, where) if choice.group is not None
                else srdf.groups[0])
        group_name = spec.name
        # (a group of links alone, an end effector's, is no choice: it moves nothing)
        moving = [g.name for g in srdf.groups if g.chains or g.joints or g.subgroups]
        if choice.group is None and len(moving) > 1:
            notes.append(f"planning group '{spec.name}', the first of "
                         f"{', '.join(moving)} (choose with --group)")
        chains, joints, links = srdf.group_joints(spec, where)
        joints += [j.name for j in chain.joints if j.child in links and j.name not in joints]
        if chains:
            base, tip = base or chains[0][0], tip or chains[0][1]
        elif joints:
            known = {j.name: j for j in chain.joints}
            unknown = [n for n in joints if n not in known]
            if unknown:
                raise RobotStructureError(f"group '{spec.name}' names joints the URDF does not "
                                          f"have: {', '.join(unknown)}", where,
                                          f"joints among {', '.join(known)}")
            planned = [known[n] for n in joints if known[n].actuated and n not in tree.mimic]
    if planned is None and (base is not None or tip is not None):
        own = [j for j in chain.actuated_joints if j.name not in tree.mimic]
        if tip is None and own:
            tip = _default_tip(chain, own[-1], {j.name for j in own})
        tip = tip or chain.links[-1].name
        base = base or chain.root
        path = _path(chain, base, tip, where)
        planned = [j for j in path if j.actuated and j.name not in tree.mimic]
    if planned is None:
        planned = _whole_tree(tree, where)
    if not planned:
        raise RobotStructureError("the planning group moves no joint", where,
                                  "a group with at least one revolute or prismatic joint")
    planned.sort(key=lambda j: len(chain.path_to(j.child)))  # an SRDF may list them in any order
    path = chain.path_to(planned[-1].child)
    if any(j not in path for j in planned):
        raise RobotStructureError(f"group '{group_name}' is branched (joints "
                                  f"{', '.join(j.name for j in planned)})", where,
                                  "a serial chain of joints")
    names = {j.name for j in planned}
    base = base or (path[path.index(planned[0])].parent)
    tip = tip or _default_tip(chain, planned[-1], names)
    if planned[-1] not in _path(chain, base, tip, where):
        raise RobotStructureError(f"tip {tip} is not moved by the group's last joint "
                                  f"{planned[-1].name}", where, "a tip below that joint")
    for name, m in tree.mimic.items():
        if m.joint in names:
            raise RobotStructureError(f"mimic joint {name} follows planned joint {m.joint}",
                                      where, "a group whose joints no other joint mimics")
    held = _held(chain, tree, names)
    if held:
        notes.append("held outside the group: " + ", ".join(f"{n}={v:g}"
                                                             for n, v in held.items()))
    fixed = tuple(_fixed_at(j, held[j.name]) if j.name in held else j for j in chain.joints)
    frames = {**chain.frames, "base_link": base, "tool0": tip}
    if "flange" not in chain.frames:
        frames["flange"] = tip
    cut = KinematicChain(chain.name, chain.links, fixed, frames, chain.notes)
    return PlanningChain(cut, group_name, base, tip, held, tuple(notes))


def _held(chain: KinematicChain, tree: UrdfTree, planned: set[str]) -> dict[str, float]:
    """The value of each movable joint outside the group (mimic joints after their leaders)."""
    held: dict[str, float] = {}
    for j in chain.actuated_joints:
        if j.name in planned or j.name in tree.mimic:
            continue
        lim = j.limits
        held[j.name] = 0.0 if lim is None or lim.contains(0.0) else (lim.lower + lim.upper) / 2
    for j in chain.actuated_joints:
        m = tree.mimic.get(j.name)
        if m is not None and j.name not in planned and m.joint not in planned:
            held[j.name] = m.multiplier * held.get(m.joint, 0.0) + m.offset
    return held


def _fixed_at(j: Joint, value: float) -> Joint:
    """Joint ``j`` turned into a fixed joint at ``value`` (rad or m)."""
    if value == 0.0:
        return replace(j, type=JointType.FIXED, limits=None)
    m = j.origin.matrix() @ j.motion(value)
    origin = Origin(tuple(float(v) for v in m[:3, 3]),  # type: ignore[arg-type]
                    matrix_to_rpy(m[:3, :3]))
    return replace(j, type=JointType.FIXED, origin=origin, limits=None)
