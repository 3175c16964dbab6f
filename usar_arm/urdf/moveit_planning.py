"""The planning-side files of the MoveIt 2 package that ``moveit.py`` does not write:
``ompl_planning.yaml``, ``sensors_3d.yaml`` and ``moveit.rviz`` (docs/conventions.md section 3).

``ompl_planning.yaml`` offers the OMPL planners usar-arm's benchmark measured
(``bench/planners.py``, results in ``bench/results/planners.json``), best first, the best as the
default. It sets ``longest_valid_segment_fraction`` so that MoveIt checks an edge at least every
:data:`EDGE_RESOLUTION_RAD` per joint, as usar-arm does: MoveIt measures a segment as the sum of
the joints' changes and the space's extent as the sum of their ranges, so the fraction is the
resolution over that sum. usar-arm also bounds the motion of any point of the robot between two
checks (5 mm); MoveIt has no such setting, which the file says. The projection
(``joints(a1,a2)``, 0.1 rad cells) is the one usar-arm's adapter gives the planners that use
one (:data:`usar_arm.planning.ompl_adapter.PROJECTED`).

The pipeline's keys differ between ROS 2 distributions and one file cannot serve both (the same
key has another type): Humble reads ``planning_plugin`` and ``request_adapters`` as strings
(time parameterisation is a request adapter), Jazzy and later read ``planning_plugins``,
``request_adapters`` and ``response_adapters`` as lists (a string there stops move_group). The
adapters are those of MoveIt's own defaults for each (``moveit_configs_utils``).
"""

from __future__ import annotations

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.model import KinematicChain
from usar_arm.urdf.srdf import GROUP

EDGE_RESOLUTION_RAD = 0.01
"""usar-arm's edge-check resolution per joint (rad or m; ``OmplOptions.resolution``)."""

CANDIDATES: dict[str, str] = {
    "RRTConnect": "RRTConnect", "RRT": "RRT", "RRTstar": "RRTstar", "PRM": "PRM",
    "PRMstar": "PRMstar", "KPIECE": "KPIECE1", "BKPIECE": "BKPIECE1", "LBKPIECE": "LBKPIECE1",
    "FMT": "FMT", "BFMT": "BFMT"}
"""The planners the package offers, by MoveIt's type name (``geometric::NAME``) -> OMPL's class:
the geometric planners MoveIt 2 registers (``PlanningContextManager::registerDefaultPlanners``,
which names the KPIECE family without OMPL's ``1``) that the ompl Python wheels bind too, so that
usar-arm's benchmark runs each one it offers."""

RANKING: tuple[tuple[str, float, float], ...] = (
    ("RRTConnect", 1.0, 0.00149), ("KPIECE", 1.0, 0.00226), ("RRT", 1.0, 0.00396),
    ("BKPIECE", 1.0, 0.00775), ("LBKPIECE", 1.0, 0.00773), ("PRM", 1.0, 0.00708),
    ("BFMT", 1.0, 0.0579), ("FMT", 1.0, 0.148), ("PRMstar", 0.0, 2.02), ("RRTstar", 0.0, 2.01))
"""(planner, verified success (fraction), median time (s)) as ``bench/planners.py`` ranked
them in ``bench/results/planners.json``, best first (tests/urdf checks the two agree), by the
rule stated there and fixed before the run: verified success first, then the median time over
the problems whose straight line is blocked; planners with the same success and medians within
1.10x of the fastest of their group are tied, and a tie is ordered alphabetically."""
PLANNERS = tuple(name for name, _, _ in RANKING)
"""The planners offered, in the measured order; the first is the default."""
RANKED_ON = "40 KR60 start/goal pairs whose straight line is blocked, in every scene"
"""The problems of that ranking (``planners.json``'s ``settings.problems``)."""

ROS_DISTROS = ("humble", "jazzy")
DEFAULT_DISTRO = "jazzy"
"""The current ROS 2 LTS (Ubuntu 24.04; Humble, on 22.04, is the previous one)."""


def segment_fraction(chain: KinematicChain, resolution: float = EDGE_RESOLUTION_RAD) -> float:
    """``longest_valid_segment_fraction`` giving ``resolution`` per joint at most."""
    extent = float(sum(chain.upper() - chain.lower()))
    return resolution / extent


def check_distro(distro: str) -> None:
    """Raise :class:`~usar_arm.core.errors.InvalidInputError` for a distribution not in
    :data:`ROS_DISTROS`."""
    if distro not in ROS_DISTROS:
        raise InvalidInputError(f"unknown ROS 2 distribution '{distro}': the package is written "
                                f"for {' or '.join(ROS_DISTROS)}")


def _pipeline(distro: str) -> list[str]:
    """The planning pipeline's plugin and adapters in ``distro``'s format."""
    if distro == "humble":
        return ["planning_plugin: ompl_interface/OMPLPlanner",
                "request_adapters: >-",
                *(f"  default_planner_request_adapters/{a}" for a in (
                    "AddTimeOptimalParameterization", "ResolveConstraintFrames",
                    "FixWorkspaceBounds", "FixStartStateBounds", "FixStartStateCollision",
                    "FixStartStatePathConstraints"))]
    return ["planning_plugins:", "  - ompl_interface/OMPLPlanner",
            "request_adapters:",
            *(f"  - default_planning_request_adapters/{a}" for a in (
                "ResolveConstraintFrames", "ValidateWorkspaceBounds", "CheckStartStateBounds",
                "CheckStartStateCollision")),
            "response_adapters:",
            *(f"  - default_planning_response_adapters/{a}" for a in (
                "AddTimeOptimalParameterization", "ValidateSolution", "DisplayMotionPath"))]


def ompl_planning_yaml(chain: KinematicChain, distro: str = DEFAULT_DISTRO) -> str:
    """The OMPL planning pipeline of the package for ROS 2 ``distro`` (:data:`ROS_DISTROS`)."""
    check_distro(distro)
    joints = list(chain.joint_names)
    projection = f"joints({','.join(joints[:2])})"
    lines = [
        f"# OMPL planning pipeline for ROS 2 {distro.capitalize()}, written by usar-arm.",
        *_pipeline(distro),
        "start_state_max_bounds_error: 0.1",
        "# Planners in the order usar-arm's benchmark ranked them (bench/results/planners.json:",
        f"# {RANKED_ON}, through usar-arm's OMPL adapter, 2 s each):",
        "# verified paths first, then median time; medians within 1.10x are a tie, ordered",
        "# alphabetically. RRTstar and PRMstar refine until the time ends, by design.",
        "planner_configs:",
    ]
    for name, success, median in RANKING:
        time = f"{median:.3g} s" if median >= 1.0 else f"{median * 1e3:.3g} ms"
        lines += [f"  {name}kConfigDefault:  # {success * 100:.0f} % verified, median {time}",
                  f"    type: geometric::{name}"]
    lines += [
        f"{GROUP}:",
        f"  default_planner_config: {PLANNERS[0]}kConfigDefault",
        "  planner_configs:", *[f"    - {name}kConfigDefault" for name in PLANNERS],
        f"  projection_evaluator: {projection}",
        f"  # edges checked every {EDGE_RESOLUTION_RAD} rad per joint at most, as usar-arm's own",
        "  # planner does (which also caps the motion of any robot point at 5 mm per check;",
        "  # MoveIt has no such setting)",
        f"  longest_valid_segment_fraction: {segment_fraction(chain):.6g}", ""]
    return "\n".join(lines)


SENSORS_3D = "\n".join([
    "# No 3D sensors: USARSim arms carry none that MoveIt's occupancy map could use.",
    "sensors: []", ""])


def moveit_rviz(chain: KinematicChain) -> str:
    """An RViz 2 layout with MoveIt's MotionPlanning display on the package's group."""
    return "\n".join([
        "Panels:",
        "  - Class: rviz_common/Displays",
        "    Name: Displays",
        "  - Class: moveit_rviz_plugin/MotionPlanning",
        "    Name: MotionPlanning",
        "Visualization Manager:",
        "  Class: \"\"",
        "  Displays:",
        "    - Class: rviz_default_plugins/Grid",
        "      Name: Grid",
        "      Enabled: true",
        "      Reference Frame: <Fixed Frame>",
        "    - Class: moveit_rviz_plugin/MotionPlanning",
        "      Name: MotionPlanning",
        "      Enabled: true",
        "      Robot Description: robot_description",
        "      Planning Request:",
        f"        Planning Group: {GROUP}",
        "        Interactive Marker Size: 0",
        "      Planning Scene Topic: /monitored_planning_scene",
        "      Planned Path:",
        "        Trajectory Topic: /display_planned_path",
        "        Loop Animation: false",
        "  Enabled: true",
        "  Global Options:",
        "    Fixed Frame: base_link",
        "  Tools:",
        "    - Class: rviz_default_plugins/Interact",
        "  Views:",
        "    Current:",
        "      Class: rviz_default_plugins/Orbit",
        "      Distance: 5.0",
        "      Focal Point: {X: 0.5, Y: 0.0, Z: 1.0}",
        "      Pitch: 0.5",
        "      Yaw: 0.8",
        f"# {chain.name}: written by usar-arm", ""])


def planning_files(chain: KinematicChain, distro: str = DEFAULT_DISTRO) -> dict[str, str]:
    """Relative path -> text of the three files (for ROS 2 ``distro``)."""
    return {"config/ompl_planning.yaml": ompl_planning_yaml(chain, distro),
            "config/sensors_3d.yaml": SENSORS_3D,
            "config/moveit.rviz": moveit_rviz(chain)}
