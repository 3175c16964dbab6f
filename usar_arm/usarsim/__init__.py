"""The USARSim wire: one frozen dataclass per message type (:mod:`.messages`), the codec
between them and text lines (:mod:`.codec`, one table of message specs; docs/protocol.md) and the
client (:class:`UsarClient`: transport, inbox, request/response exchange and robot commands)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.usarsim.client import UsarClient as UsarClient
    from usar_arm.usarsim.codec import format_message as format_message
    from usar_arm.usarsim.codec import parse_line as parse_line
    from usar_arm.usarsim.messages import Act as Act
    from usar_arm.usarsim.messages import Asta as Asta
    from usar_arm.usarsim.messages import Conf as Conf
    from usar_arm.usarsim.messages import GameInfo as GameInfo
    from usar_arm.usarsim.messages import Geo as Geo
    from usar_arm.usarsim.messages import GetConf as GetConf
    from usar_arm.usarsim.messages import GetGeo as GetGeo
    from usar_arm.usarsim.messages import GetStartPoses as GetStartPoses
    from usar_arm.usarsim.messages import Init as Init
    from usar_arm.usarsim.messages import Sen as Sen
    from usar_arm.usarsim.messages import Sta as Sta

__getattr__, __dir__, __all__ = exports(__name__, __file__)
