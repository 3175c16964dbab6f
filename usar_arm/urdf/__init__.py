"""Description files: URDF and SRDF text (:mod:`.writer`, :mod:`.srdf`) and their readers
(:mod:`.description_reader` with yourdfpy, :mod:`.srdf_reader`; the planning group cut from
the tree by :mod:`.group`), validation before anything is written (:mod:`.validate`), the
MoveIt 2 package (:mod:`.moveit`) and the Tesseract config folder (:mod:`.tesseract`;
docs/moveit-tesseract.md), with the OPW fit that picks Tesseract's IK (:mod:`.opw_fit`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.urdf.description_reader import parse_urdf
    from usar_arm.urdf.moveit import moveit_files
    from usar_arm.urdf.opw_fit import OpwFit, fit_opw
    from usar_arm.urdf.srdf import joint_limits_yaml, srdf_text
    from usar_arm.urdf.srdf_reader import parse_srdf
    from usar_arm.urdf.tesseract import TesseractConfig, TesseractOptions, tesseract_config
    from usar_arm.urdf.validate import validate
    from usar_arm.urdf.writer import urdf_text

_HOMES = {
    "moveit": ("moveit_files",),
    "opw_fit": ("OpwFit", "fit_opw"),
    "description_reader": ("parse_urdf",),
    "srdf": ("joint_limits_yaml", "srdf_text"),
    "srdf_reader": ("parse_srdf",),
    "tesseract": ("TesseractConfig", "TesseractOptions", "tesseract_config"),
    "validate": ("validate",),
    "writer": ("urdf_text",),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["OpwFit", "TesseractConfig", "TesseractOptions", "fit_opw", "joint_limits_yaml",
           "moveit_files", "parse_srdf", "parse_urdf", "srdf_text", "tesseract_config",
           "urdf_text", "validate"]

__getattr__ = exports(__name__, _HOMES)
