"""Fuzz the scene loader (usar_arm.planning.scene_file, with usar_arm.core.yamlio and PyYAML).

Contract: any file content given to ``load_scene`` gives a Scene or raises InvalidInputError
(FileFormatError naming the file, and the line and field where known); nothing else escapes.
The input is written to a scratch folder holding the shipped meshes, so mesh objects load.

    python fuzz/fuzz_scene.py -max_len=1024 -max_total_time=60 build/fuzz/scene fuzz/corpus/scene

PyYAML's pure-Python parser, instrumented, makes this the slowest target (tens of runs per
second): ``-max_len=1024`` keeps inputs short; errors need no more than a few lines.
"""

from __future__ import annotations

import math

import atheris
from _harness import run, scratch_file

with atheris.instrument_imports(include=["usar_arm", "yaml"]):
    from usar_arm.core.errors import InvalidInputError
    from usar_arm.planning.scene import Scene
    from usar_arm.planning.scene_file import load_scene

SCENE = scratch_file("scene.yaml", with_meshes=True)


def test_one_input(data: bytes) -> None:
    SCENE.write_bytes(data)
    try:
        scene = load_scene(SCENE)
    except InvalidInputError as exc:
        assert str(SCENE) in str(exc), exc
        return
    assert isinstance(scene, Scene) and isinstance(scene.name, str)
    names = [o.name for o in scene.objects]
    assert len(set(names)) == len(names), names
    for obj in scene.objects:
        assert math.isfinite(obj.bounding_radius()), obj


if __name__ == "__main__":
    run(test_one_input, "scene.dict")
