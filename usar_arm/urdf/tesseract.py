"""A Tesseract (ROS-Industrial) config folder for a described arm (docs/conventions.md
section 6).

Files, for a robot ``R`` written into a folder ``PKG`` (the folder's name is its package name:
Tesseract's ``GeneralResourceLocator`` resolves ``package://PKG/...`` to a folder called PKG
that holds a ``package.xml``, found through ``TESSERACT_RESOURCE_PATH``):

* ``R.urdf``: the description, plus a fixed ``opw_base`` frame on joint 1's axis when the OPW
  solver needs one;
* ``R.srdf``: the description's SRDF with Tesseract's ``kinematics_plugin_config`` and
  ``contact_managers_plugin_config`` entries;
* ``R.kinematics_plugins.yaml``: forward kinematics (KDL) and inverse kinematics: OPW
  (``OPWInvKin``, closed form) when the arm is OPW within the stated tolerance, measured by
  comparing OPW forward kinematics with the chain's at random configurations
  (:mod:`.opw_fit`); otherwise KDL's Levenberg-Marquardt solver, with the reason. KDL's
  Newton-Raphson solver is always offered beside the default;
* ``R.contact_managers_plugins.yaml``: Bullet and FCL discrete managers, Bullet continuous;
* ``task_composer_plugins.yaml`` (:mod:`.tesseract_composer`), ``package.xml``,
  ``plan_example.py`` (:mod:`.tesseract_example`) and ``README.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.errors import InvalidInputError, ValidationError
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.core.version import __version__
from usar_arm.urdf.opw_fit import NotOpwError, OpwFit, fit_opw
from usar_arm.urdf.srdf import GROUP
from usar_arm.urdf.tesseract_composer import PIPELINES, task_composer_yaml
from usar_arm.urdf.tesseract_example import example_script
from usar_arm.urdf.tesseract_package import check_package_name
from usar_arm.urdf.tesseract_readme import readme
from usar_arm.urdf.writer import num, nums

OPW_SOLVER = "OPWInvKin"
KDL_SOLVER = "KDLInvKinChainLMA"
KDL_NR_SOLVER = "KDLInvKinChainNR"
OPW_BASE = "opw_base"
DISCRETE_MANAGER = "BulletDiscreteBVHManager"


@dataclass(frozen=True)
class TesseractOptions:
    """How the inverse-kinematics solver is chosen.

    Attributes:
        opw_position_tolerance: m; OPW is chosen only when its forward kinematics stays this
            close to the chain's at every sampled configuration.
        opw_rotation_tolerance: rad, the same for the tool orientation.
        samples: random configurations of that comparison (uniform in the limits).
        seed: their seed.
    """

    opw_position_tolerance: float = 1e-6
    opw_rotation_tolerance: float = 1e-6
    samples: int = 1000
    seed: int = 0

    def __post_init__(self) -> None:
        if not (self.opw_position_tolerance >= 0 and self.opw_rotation_tolerance >= 0):
            raise InvalidInputError("OPW tolerances must be >= 0, got "
                                    f"{self.opw_position_tolerance} m, "
                                    f"{self.opw_rotation_tolerance} rad")
        if self.samples < 1:
            raise InvalidInputError(f"samples must be >= 1, got {self.samples}")


@dataclass(frozen=True)
class TesseractConfig:
    """A Tesseract config folder's files and the choice made.

    Attributes:
        package: the folder's name (its package name in ``package://`` URLs).
        files: relative path -> text.
        solver: the default inverse-kinematics plugin (:data:`OPW_SOLVER` or
            :data:`KDL_SOLVER`).
        reason: why that solver, with the measured numbers.
        opw: the OPW fit when one could be read (also when it was not close enough).
    """

    package: str
    files: dict[str, str]
    solver: str
    reason: str
    opw: OpwFit | None


def choose_solver(chain: KinematicChain, options: TesseractOptions
                  ) -> tuple[str, str, OpwFit | None]:
    """(solver, reason, fit): OPW when the fit's measured deviation is within tolerance."""
    try:
        fit = fit_opw(chain, "tool0", options.samples, options.seed)
    except NotOpwError as exc:
        return KDL_SOLVER, f"KDL: {exc}", None
    measured = (f"OPW forward kinematics deviates from the arm's by up to "
                f"{fit.position_error_m * 1e3:.3g} mm and {fit.rotation_error_rad * 1e3:.3g} "
                f"mrad at {fit.samples} random configurations (the wrist axes of "
                f"{' and '.join(fit.wrist_gap_joints)} pass {fit.wrist_gap_m * 1e3:.1f} mm "
                "apart)")
    tolerance = (f"{options.opw_position_tolerance * 1e3:g} mm and "
                 f"{options.opw_rotation_tolerance * 1e3:g} mrad")
    if fit.within(options.opw_position_tolerance, options.opw_rotation_tolerance):
        return OPW_SOLVER, f"OPW: {measured}, within {tolerance}", fit
    return KDL_SOLVER, f"KDL: {measured}, more than {tolerance}", fit


def _check(chain: KinematicChain, srdf: str, package: str) -> list[str]:
    problems = []
    if "</robot>" not in srdf or f'<group name="{GROUP}"' not in srdf:
        problems.append(f"the SRDF has no <robot> element with a '{GROUP}' group")
    if "plugin_config" in srdf:
        problems.append("the SRDF already names plugin configs")
    for role in ("tool0",):
        if role not in chain.frames:
            problems.append(f"the chain names no '{role}' frame")
    if any(lk.name == OPW_BASE for lk in chain.links):
        problems.append(f"the chain already has a link called '{OPW_BASE}'")
    return problems


def _plugin(name: str, factory: str, base: str, tip: str, extra: list[str] | None = None
            ) -> list[str]:
    return [f"        {name}:", f"          class: {factory}", "          config:",
            f"            base_link: {base}", f"            tip_link: {tip}", *(extra or [])]


def kinematics_yaml(chain: KinematicChain, solver: str, fit: OpwFit | None, opw_base: str,
                    reason: str) -> str:
    """The ``kinematic_plugins`` YAML of the manipulator group."""
    root, tip = chain.root, chain.frames["tool0"]
    lines = ["# Tesseract kinematics plugins, written by usar-arm.", f"# {reason}",
             "kinematic_plugins:", "  search_libraries:",
             "    - tesseract_kinematics_kdl_factories"]
    if solver == OPW_SOLVER:
        lines.append("    - tesseract_kinematics_opw_factory")
    lines += ["  fwd_kin_plugins:", f"    {GROUP}:", "      default: KDLFwdKinChain",
              "      plugins:", *_plugin("KDLFwdKinChain", "KDLFwdKinChainFactory", root, tip),
              "  inv_kin_plugins:", f"    {GROUP}:", f"      default: {solver}", "      plugins:"]
    if solver == OPW_SOLVER and fit is not None:
        p = fit.parameters
        params = ["            params:"] + [
            f"              {k}: {num(getattr(p, k))}"
            for k in ("a1", "a2", "b", "c1", "c2", "c3", "c4")]
        params += [f"              offsets: [{', '.join(num(v) for v in p.offsets)}]",
                   "              sign_corrections: "
                   f"[{', '.join(str(s) for s in p.sign_corrections)}]"]
        lines += _plugin(OPW_SOLVER, "OPWInvKinFactory", opw_base, tip, params)
    lines += _plugin(KDL_SOLVER, "KDLInvKinChainLMAFactory", root, tip)
    lines += _plugin(KDL_NR_SOLVER, "KDLInvKinChainNRFactory", root, tip)
    return "\n".join(lines) + "\n"


CONTACT_MANAGERS = "\n".join([
    "# Tesseract contact managers, written by usar-arm.",
    "contact_manager_plugins:",
    "  search_libraries:",
    "    - tesseract_collision_bullet_factories",
    "    - tesseract_collision_fcl_factories",
    "  discrete_plugins:",
    f"    default: {DISCRETE_MANAGER}",
    "    plugins:",
    "      BulletDiscreteBVHManager:",
    "        class: BulletDiscreteBVHManagerFactory",
    "      FCLDiscreteBVHManager:",
    "        class: FCLDiscreteBVHManagerFactory",
    "  continuous_plugins:",
    "    default: BulletCastBVHManager",
    "    plugins:",
    "      BulletCastBVHManager:",
    "        class: BulletCastBVHManagerFactory", ""])


def _urdf_with_frame(urdf: str, chain: KinematicChain, fit: OpwFit) -> str:
    """The URDF with a fixed ``opw_base`` frame at the OPW base pose under the root link."""
    xyz, rpy = fit.base[:3, 3], matrix_to_rpy(fit.base[:3, :3])
    frame = [f"  <!-- {OPW_BASE}: the OPW solver's base frame (on joint 1's axis), added by "
             "usar-arm tesseract-config -->",
             f'  <link name="{OPW_BASE}"/>',
             f'  <joint name="{chain.root}-{OPW_BASE}" type="fixed">',
             f'    <origin xyz="{nums(xyz)}" rpy="{nums(rpy)}"/>',
             f'    <parent link="{chain.root}"/>', f'    <child link="{OPW_BASE}"/>',
             "  </joint>"]
    head, _, tail = urdf.rpartition("</robot>")
    return head + "\n".join(frame) + "\n</robot>" + tail


def _package_xml(package: str, robot: str) -> str:
    return "\n".join([
        '<?xml version="1.0"?>', '<package format="3">', f"  <name>{package}</name>",
        "  <version>0.1.0</version>",
        f"  <description>Tesseract configuration of the USARSim {robot}, generated by usar-arm "
        f"{__version__}.</description>",
        '  <maintainer email="usar-arm@example.invalid">usar-arm</maintainer>',
        "  <license>Apache-2.0</license>", "</package>", ""])


def tesseract_config(chain: KinematicChain, urdf: str, srdf: str, package: str,
                     home: dict[str, float] | None = None,
                     options: TesseractOptions | None = None) -> TesseractConfig:
    """Every file of a Tesseract config folder called ``package`` for ``chain``, whose URDF and
    SRDF texts are ``urdf`` and ``srdf``; ``home`` (rad, m; default all zero) starts the
    example's motion.

    Raises:
        InvalidInputError: the folder name cannot be a ROS package name (REP-144).
        ValidationError: listing every problem of the SRDF and the chain.
    """
    options = options or TesseractOptions()
    check_package_name(package, chain.name)
    problems = _check(chain, srdf, package)
    if problems:
        raise ValidationError(f"Tesseract config of {chain.name}", problems)
    solver, reason, fit = choose_solver(chain, options)
    robot, root, tip = chain.name, chain.root, chain.frames["tool0"]
    opw_base = root
    if solver == OPW_SOLVER and fit is not None and not np.allclose(
            fit.base, np.eye(4), rtol=0.0, atol=1e-12):
        urdf, opw_base = _urdf_with_frame(urdf, chain, fit), OPW_BASE
    entries = (f'  <kinematics_plugin_config filename="package://{package}/'
               f'{robot}.kinematics_plugins.yaml"/>\n'
               f'  <contact_managers_plugin_config filename="package://{package}/'
               f'{robot}.contact_managers_plugins.yaml"/>\n')
    head, _, tail = srdf.rpartition("</robot>")
    start = [float((home or {}).get(j.name, 0.0)) for j in chain.actuated_joints]
    goal = list(start)
    limits = chain.actuated_joints[0].limits
    if limits is not None:
        goal[0] = limits.clamp(start[0] + 0.5)
    files = {
        f"{robot}.urdf": urdf,
        f"{robot}.srdf": head + entries + "</robot>" + tail,
        f"{robot}.kinematics_plugins.yaml": kinematics_yaml(chain, solver, fit, opw_base,
                                                            reason),
        f"{robot}.contact_managers_plugins.yaml": CONTACT_MANAGERS,
        "task_composer_plugins.yaml": task_composer_yaml(),
        "package.xml": _package_xml(package, robot),
    }
    script = example_script(robot, GROUP, root, tip, solver, start, goal)
    files["plan_example.py"] = script
    files["README.md"] = readme(robot, package, sorted([*files, "README.md"]), solver, reason,
                                tuple(PIPELINES), script)
    return TesseractConfig(package, files, solver, reason, fit)
