"""Attached-body files (YAML or JSON) and entries: what ``usar-arm plan --attach FILE`` and a
batch problem's ``attach`` give, checked field by field.

Format (lengths in m, angles in rad; the pose is the object's in the link's frame)::

    name: bar                         # the object's name (a new link of that name carries it)
    link: KR60gripper_tcp             # the link it is fixed to (default: tool0)
    box: [1.2, 0.04, 0.04]            # or cylinder: {radius, length}, sphere: {radius},
                                      # mesh: {file, scale} (relative to this file)
    xyz: [0, 0, 0.05]                 # the grasp: its centre in the link's frame
    rpy: [0, 0, 0]                    # optional
    touch_links: [KR60gripper]        # optional: links it may touch

An entry without a shape (``{name: part, link: ..., touch_links: [...]}``) names a scene object,
to be taken from the scene at the configuration it is attached at (:class:`AttachRequest`).
Every error names the file, the line and the field, as scene files do.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.cell import SHAPES, CellReader, read_yaml_file
from usar_arm.core.errors import FileFormatError
from usar_arm.core.shapes import Box, CylinderShape, ObstacleShape, Sphere
from usar_arm.core.spatial import Array, matrix_to_rpy
from usar_arm.core.yamlio import line_of
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.cell_scene import solid

KEYS = {"name", "link", "xyz", "rpy", "touch_links", *SHAPES}
DEFAULT_LINK = "tool0"


@dataclass(frozen=True, eq=False)
class AttachRequest:
    """An object to attach: a new one (``shape`` and ``pose`` given) or a scene object's name.

    Attributes:
        name: the object. link: the link to fix it to (None: not given, :data:`DEFAULT_LINK`
            unless the caller names one). touch_links: links it may touch.
        shape, pose: a new object's geometry and 4x4 pose in the link's frame (None: take the
            scene object's at the configuration it is attached at).
    """

    name: str
    link: str | None = None
    touch_links: tuple[str, ...] = ()
    shape: ObstacleShape | None = None
    pose: Array | None = None

    def body(self) -> AttachedBody:
        """The body of a new object (FileFormatError-free: ``shape`` and ``pose`` are set)."""
        assert self.shape is not None and self.pose is not None
        return AttachedBody(self.name, self.link or DEFAULT_LINK, self.shape, self.pose,
                            self.touch_links)


def parse_attach(data: Any, path: str, base: Path, field: str = "") -> AttachRequest:
    """An :class:`AttachRequest` from parsed YAML/JSON (``base``: the folder of a relative mesh
    file; ``field``: where the entry is, for messages, e.g. ``attach``)."""
    reader = CellReader(path, base)
    at = f"{field}." if field else ""
    if not isinstance(data, dict):
        raise FileFormatError(path, f"expected a mapping with name, link, a shape and xyz, "
                                    f"got {data!r}"[:200], line=line_of(data), field=field or None)
    unknown = sorted((k for k in data if k not in KEYS), key=str)
    if unknown:
        raise reader.fail(f"unknown key '{unknown[0]}' (expected: {', '.join(sorted(KEYS))})",
                          data, unknown[0], f"{at}{unknown[0]}")
    name = data.get("name")
    if not isinstance(name, str) or not name:
        raise reader.fail("the object needs a 'name'", data, "name" if "name" in data else None,
                          f"{at}name")
    link = data.get("link")
    if link is not None and (not isinstance(link, str) or not link):
        raise reader.fail(f"'link' names a robot link, got {link!r}", data, "link", f"{at}link")
    touch = data.get("touch_links", [])
    if not isinstance(touch, list) or not all(isinstance(t, str) and t for t in touch):
        raise reader.fail("'touch_links' must be a list of link names", data, "touch_links",
                          f"{at}touch_links")
    kinds = [k for k in SHAPES if k in data]
    if len(kinds) > 1:
        raise reader.fail(f"'{name}' has more than one shape ({', '.join(kinds)})", data, None,
                          field or name)
    if not kinds:
        extra = [k for k in ("xyz", "rpy") if k in data]
        if extra:
            raise reader.fail(f"'{extra[0]}' without a shape: give one of "
                              f"{', '.join(SHAPES)}, or leave out the pose to take the scene "
                              f"object '{name}' as it stands", data, extra[0],
                              f"{at}{extra[0]}")
        return AttachRequest(name, link, tuple(touch))
    shape = reader.shape(data, kinds[0], field or name)
    body = solid(shape, path)
    pose = reader.pose(data, name, field or name)
    return AttachRequest(name, link, tuple(touch), body, pose)


def read_attach(path: str | Path) -> AttachRequest:
    """:func:`parse_attach` of a YAML or JSON file."""
    p = Path(path)
    return parse_attach(read_yaml_file(p, str(p)), str(p), p.parent)


def _num(value: float) -> str:
    """A float as YAML reads it back exactly (``repr``, with the point YAML 1.1 needs before
    an exponent: ``1e-08`` would read as text)."""
    text = repr(float(value))
    mantissa, e, exponent = text.partition("e")
    return f"{mantissa}.0e{exponent}" if e and "." not in mantissa else text


def attach_text(body: AttachedBody) -> str:
    """A body as the YAML of this format (numbers exact); a mesh is not written
    (it names its file)."""
    s = body.shape
    if isinstance(s, Box):
        shape = f"box: [{', '.join(_num(v) for v in s.size)}]"
    elif isinstance(s, CylinderShape):
        shape = f"cylinder: {{radius: {_num(s.radius)}, length: {_num(s.length)}}}"
    elif isinstance(s, Sphere):
        shape = f"sphere: {{radius: {_num(s.radius)}}}"
    else:
        raise ValueError(f"'{body.name}' is a mesh: its file is the description")
    xyz = ", ".join(_num(v) for v in np.asarray(body.pose)[:3, 3])
    rpy = ", ".join(_num(v) for v in matrix_to_rpy(np.asarray(body.pose)[:3, :3]))
    touch = ", ".join(json.dumps(t) for t in body.touch_links)
    return (f"name: {json.dumps(body.name)}\nlink: {json.dumps(body.link)}\n{shape}\n"
            f"xyz: [{xyz}]\nrpy: [{rpy}]\ntouch_links: [{touch}]\n")
