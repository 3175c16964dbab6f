"""The planning-side files of the MoveIt 2 package that ``moveit.py`` does not write:
``ompl_planning.yaml``, ``sensors_3d.yaml`` and ``moveit.rviz`` (docs/conventions.md section 3).

``ompl_planning.yaml`` names RRTConnect as the default (the planner usar-arm's benchmark uses)
and sets ``longest_valid_segment_fraction`` so that MoveIt checks an edge at least every
:data:`EDGE_RESOLUTION_RAD` per joint, as usar-arm does. MoveIt measures a segment as the sum of
the joints' changes and the space's extent as the sum of their ranges, so the fraction is the
resolution over that sum. usar-arm also bounds the motion of any point of the robot between two
checks (5 mm); MoveIt has no such setting, which the file says.
"""

from __future__ import annotations

from usar_arm.model import KinematicChain
from usar_arm.urdf.srdf import GROUP

EDGE_RESOLUTION_RAD = 0.01
"""usar-arm's edge-check resolution per joint (rad or m; ``OmplOptions.resolution``)."""

PLANNERS = ("RRTConnect", "RRT", "RRTstar", "PRM", "PRMstar", "KPIECE1", "BKPIECE1",
            "LBKPIECE1")
"""OMPL geometric planners offered, the default first: those the ``ompl`` Python wheels bind too,
so that usar-arm can run each one it offers MoveIt."""


def segment_fraction(chain: KinematicChain, resolution: float = EDGE_RESOLUTION_RAD) -> float:
    """``longest_valid_segment_fraction`` giving ``resolution`` per joint at most."""
    extent = float(sum(chain.upper() - chain.lower()))
    return resolution / extent


def ompl_planning_yaml(chain: KinematicChain) -> str:
    """The OMPL planning pipeline of the package, for Humble (``planning_plugin``) and Jazzy
    and later (``planning_plugins``)."""
    joints = list(chain.joint_names)
    projection = f"joints({','.join(joints[:2])})"
    lines = [
        "# OMPL planning pipeline, written by usar-arm.",
        "planning_plugin: ompl_interface/OMPLPlanner  # ROS 2 Humble",
        "planning_plugins:  # ROS 2 Jazzy and later",
        "  - ompl_interface/OMPLPlanner",
        "start_state_max_bounds_error: 0.1",
        "planner_configs:",
    ]
    for name in PLANNERS:
        lines += [f"  {name}kConfigDefault:", f"    type: geometric::{name}"]
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


def planning_files(chain: KinematicChain) -> dict[str, str]:
    """Relative path -> text of the three files."""
    return {"config/ompl_planning.yaml": ompl_planning_yaml(chain),
            "config/sensors_3d.yaml": SENSORS_3D,
            "config/moveit.rviz": moveit_rviz(chain)}
