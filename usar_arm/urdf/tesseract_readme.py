"""The README.md of a Tesseract config folder: what is in it, which solver and why, how to load
it, and the example that plans with it."""

from __future__ import annotations

from collections.abc import Sequence

from usar_arm.core.version import __version__


def readme(robot: str, package: str, files: Sequence[str], solver: str, reason: str,
           pipelines: Sequence[str], script: str) -> str:
    """README.md text; ``script`` is quoted whole."""
    listing = "\n".join(f"* `{name}`" for name in files)
    return f"""# {package}: Tesseract configuration of the {robot}

Written by usar-arm {__version__} (`usar-arm tesseract-config`) for Tesseract 0.28
(`pip install tesseract-robotics==0.5.1`, Python 3.11). Lengths in metres, angles in radians.

{listing}

Inverse kinematics: `{solver}`. {reason}.
Forward kinematics: KDL from the URDF. Collision: `BulletDiscreteBVHManager` (default) and
`FCLDiscreteBVHManager`, `BulletCastBVHManager` for continuous checks. The SRDF keeps the
disabled collision pairs usar-arm computed and adds Tesseract's
`kinematics_plugin_config` and `contact_managers_plugin_config` entries, which point into this
folder as `package://{package}/...`: Tesseract's `GeneralResourceLocator` finds the folder
by its name (keep it, or regenerate) through `TESSERACT_RESOURCE_PATH`, set to this folder or
its parent.

`task_composer_plugins.yaml` defines the pipelines {", ".join(f"`{p}`" for p in pipelines)}
(Tesseract's wheel ships none); with an empty `ProfileDictionary` each task uses Tesseract's
default profile.

## Plan with it

`python plan_example.py [PIPELINE]` (in the venv with tesseract-robotics):

```python
{script.rstrip()}
```
"""
