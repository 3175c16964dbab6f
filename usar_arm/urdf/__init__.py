"""Description files: URDF and SRDF text (:mod:`.writer`, :mod:`.srdf`) and their readers
(:mod:`.description_reader` with yourdfpy, :mod:`.srdf_reader`; the planning group cut from
the tree by :mod:`.group`), validation before anything is written (:mod:`.validation`), the
MoveIt 2 package (:mod:`.moveit`) and the Tesseract config folder (:mod:`.tesseract`;
docs/moveit-tesseract.md), with the OPW fit that picks Tesseract's IK (:mod:`.opw_fit`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.urdf.description_reader import parse_urdf as parse_urdf
    from usar_arm.urdf.moveit import moveit_files as moveit_files
    from usar_arm.urdf.opw_fit import OpwFit as OpwFit
    from usar_arm.urdf.opw_fit import fit_opw as fit_opw
    from usar_arm.urdf.srdf import joint_limits_yaml as joint_limits_yaml
    from usar_arm.urdf.srdf import srdf_text as srdf_text
    from usar_arm.urdf.srdf_reader import parse_srdf as parse_srdf
    from usar_arm.urdf.tesseract import TesseractConfig as TesseractConfig
    from usar_arm.urdf.tesseract import TesseractOptions as TesseractOptions
    from usar_arm.urdf.tesseract import tesseract_config as tesseract_config
    from usar_arm.urdf.validation import validate as validate
    from usar_arm.urdf.writer import urdf_text as urdf_text

__getattr__, __dir__, __all__ = exports(__name__, __file__)
