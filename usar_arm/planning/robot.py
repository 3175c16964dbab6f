"""A described arm, ready for IK, collision checking and planning: :class:`Robot`, built from
a description's files (:func:`robot_from_files`, :func:`robot_from_texts`). A freshly learnt
arm becomes one through :func:`usar_arm.description.cache.robot_from_record`."""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from usar_arm.core.attach_errors import AttachedCollisionError
from usar_arm.core.errors import FileFormatError
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.acm import adjacent_pairs, default_state
from usar_arm.planning.attached import AttachedBody, carrying
from usar_arm.planning.collision import CollisionWorld, Pair
from usar_arm.planning.ik import IKOptions, IKSolver
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.scene import EMPTY, Mesh, Scene
from usar_arm.planning.scene_file import validate_allow
from usar_arm.urdf.description_reader import ReadOptions, read_urdf
from usar_arm.urdf.discovery_file import discovery_document, wire_facts
from usar_arm.urdf.group import GroupChoice, cut_chain
from usar_arm.urdf.joint_limits import apply_joint_limits_text
from usar_arm.urdf.kinematic_text import kinematic_urdf
from usar_arm.urdf.packages import PackagePaths
from usar_arm.urdf.srdf_reader import Srdf, read_srdf

log = logging.getLogger("usar_arm.planning.robot")


@dataclass(frozen=True)
class RobotOptions:
    """How to read a description (picklable: worker processes rebuild the arm with it).

    Attributes:
        choice: the planning group, base and tip links (default: the SRDF's first group, or
            the whole tree when it is one chain). read: where resources are, convex hulls.
    """

    choice: GroupChoice = field(default_factory=GroupChoice)
    read: ReadOptions = field(default_factory=ReadOptions)

    @classmethod
    def of(cls, group: str | None = None, base: str | None = None, tip: str | None = None,
           package_paths: Mapping[str, str] | None = None, convex_hull: bool = False
           ) -> RobotOptions:
        """Options from plain values.

        Args:
            group: the SRDF planning group (default: its first, or the whole URDF when it is
                one chain). base: plan the chain from this link instead of a group.
            tip: the tool frame poses refer to (``tool0``; default: the group's tip, tool0
                below its last joint, or the chain's last link down fixed joints).
            package_paths: package name -> folder for ``package://`` meshes (searched before
                ROS_PACKAGE_PATH, AMENT_PREFIX_PATH and the URDF's ancestors).
            convex_hull: the collision meshes replaced by their convex hulls.
        """
        return cls(GroupChoice(group, base, tip),
                   ReadOptions(PackagePaths(dict(package_paths or {})), convex_hull))


@dataclass
class Robot:
    """An arm's description and the solvers built on it.

    Attributes:
        chain: the kinematic chain (limits with acceleration and jerk when known).
        urdf: its URDF text. disabled: the SRDF's disabled collision pairs.
        states: the SRDF's named states (``home``...), joint name -> value.
        actuator: the USARSim actuator that moves it (for ACT), when known.
        source: where the description came from (for messages).
    """

    chain: KinematicChain
    urdf: str
    disabled: set[Pair] = field(default_factory=set)
    states: dict[str, dict[str, float]] = field(default_factory=dict)
    actuator: str | None = None
    source: str = ""
    wire_links: tuple[int, ...] = ()
    """USARSim link number (1-based, as in ASTA) of each joint, in joint order."""
    tip_sensor: str | None = None
    """Name of the server's tip GroundTruth sensor (and of its URDF frame), when it has one."""
    files: dict[str, str] = field(default_factory=dict)
    """The description's files (name -> text: URDF, SRDF, joint limits, discovery notes)."""
    kinematic_urdf: str = ""
    """The planning chain's kinematics as URDF text for Pinocchio (empty: ``urdf``)."""
    options: RobotOptions = field(default_factory=RobotOptions)
    """How the description was read (group, tip, packages, hulls)."""
    carried: tuple[AttachedBody, ...] = ()
    """The objects this robot carries (each a link of ``chain``; :meth:`carrying`)."""
    _kinematics: KinematicModel | None = None
    _ik: dict[tuple[str, IKOptions], IKSolver] = field(default_factory=dict)
    _worlds: dict[tuple[float, frozenset[Pair]], CollisionWorld] = field(
        default_factory=dict, init=False, repr=False, compare=False)
    _bare: Robot | None = field(default=None, repr=False, compare=False)
    _carrying: dict[tuple[object, ...], Robot] = field(
        default_factory=dict, init=False, repr=False, compare=False)

    @property
    def kinematics(self) -> KinematicModel:
        """The Pinocchio model (built on first use)."""
        if self._kinematics is None:
            self._kinematics = KinematicModel(self.kinematic_urdf or self.urdf,
                                              self.chain.joint_names, self.chain.frames)
        return self._kinematics

    def ik_solver(self, options: IKOptions | None = None, frame: str = "tool0") -> IKSolver:
        """An IK solver of ``frame`` (cached per options)."""
        key = (frame, options or IKOptions())
        if key not in self._ik:
            self._ik[key] = IKSolver(self.chain, self.kinematics, frame, key[1])
        return self._ik[key]

    def collision_world(self, scene: Scene = EMPTY, padding: float = 0.0) -> CollisionWorld:
        """A collision world of this arm in ``scene`` (a new one each call).

        What depends on the arm alone (the bodies fitted to its meshes, their FCL geometry,
        the pairs proven never in contact, the lever arms) is built once, in a world of the
        empty scene per padding and set of disabled pairs, that every later world is copied
        from (:meth:`CollisionWorld.in_scene`): a world per scene costs the scene's part only.
        A scene object of a carried body's name is that body (:meth:`carrying`): it is not an
        obstacle of the world.
        """
        carried = {b.name for b in self.carried}
        if any(o.name in carried for o in scene.objects):
            scene = Scene(scene.name, tuple(o for o in scene.objects if o.name not in carried))
        validate_allow(scene, {lk.name for lk in self.chain.links})
        key = (float(padding), frozenset(self.disabled))
        base = self._worlds.get(key)
        if base is None:
            base = CollisionWorld(self.chain, self.kinematics, self.disabled, EMPTY, padding)
            base.lever_arms()  # (computed here, so that the copies carry them)
            self._worlds[key] = base
        return base.in_scene(scene)

    @property
    def bare(self) -> Robot:
        """This arm carrying nothing (itself when it carries nothing)."""
        return self._bare or self

    def carrying(self, bodies: Sequence[AttachedBody]) -> Robot:
        """This arm carrying exactly ``bodies`` (whatever this robot carries now): a Robot
        whose chain has each body as a link fixed to its parent link (its parent and touch
        links never checked against it), with the same states, actuator, files and options.
        Cached per set of bodies; an empty ``bodies`` is the bare arm.

        What it costs: the kinematics and, on first use, one collision world per padding (the
        compiled verdicts' arrays, FCL's objects and the never-in-contact proof of the links,
        the bodies' included: the kernels are compiled once for every chain, so this is
        milliseconds, not the first world's compile time); a mesh body also costs its ball
        cover (:mod:`.ball_cover`, once per mesh in a process, growing with its area).

        Raises:
            AttachError: an unknown link, a name that is a link's or another body's.
        """
        bare = self.bare
        bodies = tuple(bodies)
        if not bodies:
            return bare
        key = tuple(b.key() for b in bodies)
        found = bare._carrying.get(key)
        if found is None:
            chain, disabled = carrying(bare.chain, bare.disabled, bodies)
            found = Robot(chain, bare.urdf, disabled, bare.states, bare.actuator, bare.source,
                          bare.wire_links, bare.tip_sensor, bare.files, kinematic_urdf(chain),
                          bare.options, bodies, _bare=bare)
            bare._carrying[key] = found
        return found

    def check_attachable(self, body: AttachedBody, q: Array, scene: Scene = EMPTY) -> None:
        """Refuse to attach ``body`` where it is in collision at ``q`` (rad/m) with anything
        but its parent and touch links: a robot link, a body carried already, or an object of
        ``scene`` (the object called ``body.name`` aside: it is the one being attached).

        Raises:
            AttachedCollisionError: naming each pair in contact and its depth (m).
            AttachError: an unknown link or a name clash.
        """
        others = tuple(b for b in self.carried if b.name != body.name)
        robot = self.carrying((*others, body))
        rest = Scene(scene.name, tuple(o for o in scene.objects if o.name != body.name))
        world = robot.collision_world(rest)
        found = [(c.a if c.b == body.name else c.b, c.depth)
                 for c in world.contact_details(np.asarray(q, float))
                 if body.name in (c.a, c.b)]
        if found:
            raise AttachedCollisionError(body.name, [(body.name, o, d) for o, d in found])

    def home(self) -> list[float]:
        """The ``home`` state, or without one each joint at 0 (the middle of its limits when 0
        is outside them), rad or m."""
        if "home" in self.states:
            return self.named_state("home")
        return [float(v) for v in default_state(self.chain)]

    def named_state(self, name: str) -> list[float]:
        """A named state (``home``) in joint order."""
        if name not in self.states:
            raise KeyError(f"no state '{name}'; states: {', '.join(self.states) or 'none'}")
        values = self.states[name]
        return [values[j] for j in self.chain.joint_names]


def robot_from_files(urdf: str | Path, srdf: str | Path | None = None,
                     joint_limits: str | Path | None = None,
                     options: RobotOptions | None = None) -> Robot:
    """A Robot from a URDF (and SRDF, joint_limits.yaml; found beside the URDF when not given,
    as ``<Robot>.srdf`` and ``<Robot>.joint_limits.yaml``, with ``<Robot>.discovery.json``),
    read with ``options`` (group, base and tip links, package paths, convex hulls)."""
    path = Path(urdf)
    try:
        text = path.read_text()
    except OSError as exc:
        raise FileFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    stem = path.name.removesuffix(".urdf")
    srdf_path = Path(srdf) if srdf else path.with_name(f"{stem}.srdf")
    if srdf and not srdf_path.exists():
        raise FileFormatError(str(srdf_path), "no such SRDF file")
    limits_path = Path(joint_limits) if joint_limits else path.with_name(
        f"{stem}.joint_limits.yaml")
    info = path.with_name(f"{stem}.discovery.json")
    roles = {f"{stem}.srdf": srdf_path, f"{stem}.joint_limits.yaml": limits_path,
             f"{stem}.discovery.json": info}
    files = {path.name: text, **{name: p.read_text() for name, p in roles.items()
                                 if p.exists()}}
    return robot_from_texts(files, path.name, str(path), options)


def robot_from_texts(files: dict[str, str], urdf_name: str | None = None,
                     source: str = "", options: RobotOptions | None = None,
                     carried: Sequence[AttachedBody] = ()) -> Robot:
    """A Robot from a description's files given as text (name -> text): ``X.urdf`` and, when
    present, ``X.srdf``, ``X.joint_limits.yaml`` and ``X.discovery.json``, carrying
    ``carried`` (:meth:`Robot.carrying`). What a worker process builds its arm from (the
    files and bodies travel by value; the solvers do not pickle)."""
    robot = _robot_from_texts(files, urdf_name, source, options)
    return robot.carrying(carried) if carried else robot


def _robot_from_texts(files: dict[str, str], urdf_name: str | None, source: str,
                      options: RobotOptions | None) -> Robot:
    if urdf_name is None:
        names = [n for n in files if n.endswith(".urdf")]
        if len(names) != 1:
            raise FileFormatError(source or "<description>",
                                  f"expected one .urdf file, got {names or 'none'}")
        urdf_name = names[0]
    stem = urdf_name.removesuffix(".urdf")
    where = source or urdf_name
    text = files[urdf_name]
    options = options or RobotOptions()
    tree = read_urdf(text, where, options.read)
    for note in tree.notes:
        log.warning("%s: %s", where, note)
    srdf = read_srdf(files[f"{stem}.srdf"], f"{stem}.srdf") if f"{stem}.srdf" in files else None
    cut = cut_chain(tree, srdf, options.choice, where)
    for note in cut.notes:
        log.warning("%s: %s", where, note)
    if any(isinstance(c.shape, Mesh) and c.shape.convex_hull
           for lk in cut.chain.links for c in lk.collisions):
        log.warning("%s: convex hulls stand in for the collision meshes (--convex-hull)", where)
    chain = cut.chain
    disabled, states = (srdf or Srdf()).disabled, (srdf or Srdf()).states
    unlisted = adjacent_pairs(chain) - disabled
    if unlisted:  # as MoveIt's setup assistant and Drake do: touching neighbours never count
        log.info("%s: adjacent links not checked against each other: %s", where,
                 ", ".join(f"{a}-{b}" for a, b in sorted(unlisted)))
        disabled = disabled | unlisted
    if f"{stem}.joint_limits.yaml" in files:
        chain = apply_joint_limits_text(chain, files[f"{stem}.joint_limits.yaml"],
                                        f"{stem}.joint_limits.yaml")
    actuator, links, tip_sensor = None, tuple(range(1, chain.dof + 1)), None
    doc = discovery_document(files, stem)
    if doc is not None:
        facts = wire_facts(doc)
        chain = KinematicChain(chain.name, chain.links, chain.joints,
                               {**chain.frames, **facts.frames}, chain.notes)
        actuator, links, tip_sensor = facts.actuator, facts.links, facts.tip_sensor
    return Robot(chain, text, disabled, states, actuator, where, links, tip_sensor,
                 dict(files), kinematic_urdf(chain), options)
