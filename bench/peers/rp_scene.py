"""roboplan Scene set-up shared by the roboplan runners (runs in the roboplan venv)."""

from pathlib import Path

from roboplan import core


def load(spec: dict) -> tuple["core.Scene", str, list[str], str]:
    """(scene, group name, the group's joint names, how collisions were filtered).

    SRDF: the problem's "srdf", else <urdf stem>.srdf beside the URDF (mplib's own rule), whose
    groups and disabled pairs importSrdf applies; with none, allowAdjacentLinkCollisions().
    Group: the problem's "group" (default "manipulator") if the SRDF defines it, else one
    built with addGroupFromChain(base_link, tip_link)."""
    scene = core.Scene("robot", core.loadUrdfSceneDescription(spec["urdf"]))
    srdf = spec.get("srdf") or Path(spec["urdf"]).with_suffix(".srdf")
    if Path(srdf).is_file():
        scene.importSrdf(Path(srdf).read_text())
        acm = f"srdf {srdf}"
    else:
        scene.allowAdjacentLinkCollisions()
        acm = "no srdf: adjacent links allowed to touch"
    group = spec.get("group", "manipulator")
    try:
        scene.getJointGroupInfo(group)
    except RuntimeError:  # not defined by the SRDF
        group = "chain"
        scene.addGroupFromChain(
            group, spec.get("base_link", "base_link"), spec.get("tip_link", "tool0")
        )
    return scene, group, list(scene.getJointGroupInfo(group).joint_names), acm
