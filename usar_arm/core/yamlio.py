"""YAML loading that remembers line numbers, so a file error can name its line and field.

Mappings load as :class:`LineDict` and sequences as :class:`LineList`; both know the 1-based
line of each key/item. Only safe YAML tags are accepted.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from usar_arm.core.errors import FileFormatError


class LineDict(dict):  # type: ignore[type-arg]
    """A dict that knows the line of each key (``lines[key]``) and of itself (``line``)."""

    line: int = 0
    lines: dict[Any, int]


class LineList(list):  # type: ignore[type-arg]
    """A list that knows the line of each item (``lines[i]``) and of itself (``line``)."""

    line: int = 0
    lines: list[int]


class _Loader(yaml.SafeLoader):
    pass


def _mapping(loader: _Loader, node: yaml.MappingNode) -> LineDict:
    out = LineDict()
    out.line = node.start_mark.line + 1
    out.lines = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None, None, "a key must be a plain value, not a mapping or a list",
                key_node.start_mark) from None
        out[key] = loader.construct_object(value_node, deep=True)
        out.lines[key] = key_node.start_mark.line + 1
    return out


def _sequence(loader: _Loader, node: yaml.SequenceNode) -> LineList:
    out = LineList(loader.construct_object(child, deep=True) for child in node.value)
    out.line = node.start_mark.line + 1
    out.lines = [child.start_mark.line + 1 for child in node.value]
    return out


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)
_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, _sequence)


def load_yaml(path: str | Path) -> Any:
    """Parse a YAML file; syntax errors become FileFormatError with the line."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise FileFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        line = p.read_bytes()[:exc.start].count(b"\n") + 1
        raise FileFormatError(str(path), f"not UTF-8 text (byte 0x{exc.object[exc.start]:02x} "
                              f"at offset {exc.start})", line=line) from None
    return loads_yaml(text, str(path))


def loads_yaml(text: str, name: str = "<string>") -> Any:
    """Parse YAML text; syntax errors become FileFormatError with the line."""
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.constructor.ConstructorError as exc:  # e.g. a mapping used as a key
        mark = exc.problem_mark or exc.context_mark
        raise FileFormatError(name, f"not valid YAML: {exc.problem or exc}",
                              line=None if mark is None else mark.line + 1) from None
    except (ValueError, TypeError, AttributeError, IndexError, KeyError, OverflowError,
            RecursionError) as exc:
        # PyYAML's constructors fail this way on values such as 2001-02-30 or "-_" as a float
        raise FileFormatError(name, f"not valid YAML: a value could not be read ({exc})"
                              ) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = None if mark is None else mark.line + 1
        problem = getattr(exc, "problem", None) or str(exc)
        raise FileFormatError(name, f"not valid YAML: {problem}", line=line) from None


def line_of(container: Any, key: Any = None) -> int | None:
    """The line of ``container[key]`` (or of the container), when known."""
    if key is not None and isinstance(container, LineDict):
        return container.lines.get(key, container.line)
    if key is not None and isinstance(container, LineList) and 0 <= key < len(container.lines):
        return container.lines[key]
    return getattr(container, "line", None) or None
