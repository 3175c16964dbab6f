"""The USARSim wire: one frozen dataclass per message type (:mod:`.messages`), the codec
between them and text lines (:mod:`.codec`, one table of message specs; docs/protocol.md) and the
client (:class:`UsarClient`: transport, inbox, request/response exchange and robot commands)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.usarsim.client import UsarClient
    from usar_arm.usarsim.codec import format_message, parse_line
    from usar_arm.usarsim.messages import (
        Act,
        Asta,
        Conf,
        GameInfo,
        Geo,
        GetConf,
        GetGeo,
        GetStartPoses,
        Init,
        Sen,
        Sta,
    )

_HOMES = {
    "client": ("UsarClient",),
    "codec": ("format_message", "parse_line"),
    "messages": ("Act", "Asta", "Conf", "GameInfo", "Geo", "GetConf", "GetGeo", "GetStartPoses",
        "Init", "Sen", "Sta"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["Act", "Asta", "Conf", "GameInfo", "Geo", "GetConf", "GetGeo", "GetStartPoses", "Init",
           "Sen", "Sta", "UsarClient", "format_message", "parse_line"]

__getattr__ = exports(__name__, _HOMES)
