"""``--attach OBJECT --attach-link LINK --touch-links A,B``: what ``usar-arm plan`` carries."""

from __future__ import annotations

import argparse
from pathlib import Path

from usar_arm.arm.facade import Arm
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import Array
from usar_arm.planning.attach_file import DEFAULT_LINK, AttachRequest, read_attach
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.scene_file import load_scene

FILE_SUFFIXES = (".json", ".yaml", ".yml")


def add_attach_args(p: argparse.ArgumentParser) -> None:
    """The options of an attached object."""
    p.add_argument("--attach", default=None, metavar="OBJECT",
                   help="carry an object: a --scene object's name (grasped where it stands at "
                        "the start configuration) or a JSON/YAML file of a body (name, link, "
                        "shape, xyz/rpy in the link frame, touch_links; docs/library.md)")
    p.add_argument("--attach-link", default=None, metavar="LINK",
                   help=f"the link it is fixed to (default: the file's, else {DEFAULT_LINK})")
    p.add_argument("--touch-links", default="", metavar="A,B",
                   help="links it may touch (the gripper holding it), comma-separated")


def attach_request(args: argparse.Namespace) -> AttachRequest | None:
    """The object --attach names (None without it); a usage error for the other two alone."""
    if args.attach is None:
        if args.attach_link or args.touch_links:
            raise InvalidInputError("--attach-link and --touch-links need --attach OBJECT")
        return None
    path = Path(args.attach)
    request = (read_attach(path) if path.suffix.lower() in FILE_SUFFIXES or path.exists()
               else AttachRequest(args.attach))
    if request.shape is None and not args.scene:
        raise InvalidInputError(f"--attach {args.attach}: a scene object's name needs --scene "
                                "(or give a body file with its shape)")
    if args.attach_link and request.link and args.attach_link != request.link:
        raise InvalidInputError(f"--attach-link {args.attach_link} contradicts the file's link "
                                f"'{request.link}' ({args.attach})")
    touch = tuple(t.strip() for t in args.touch_links.split(",") if t.strip())
    return AttachRequest(request.name, args.attach_link or request.link or DEFAULT_LINK,
                         tuple(dict.fromkeys((*request.touch_links, *touch))), request.shape,
                         request.pose)


def attach_from_args(arm: Arm, args: argparse.Namespace, start: Array | None
                     ) -> AttachedBody | None:
    """Attach the --attach object to ``arm`` at ``start`` (None: the arm's joints or home)."""
    request = attach_request(args)
    if request is None:
        return None
    scene = load_scene(args.scene) if request.shape is None else None
    return arm.attach(request.name, request.link or DEFAULT_LINK, scene=scene,
                      shape=request.shape, pose=request.pose,
                      touch_links=request.touch_links, q=start)
