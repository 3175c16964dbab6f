"""The rules of a Ray address (``--ray ADDRESS``), in one place for the executable's early
start, the command's option, the job's backend and Ray's own start.

``local`` always starts a fresh Ray instance on this machine and stops it at the end; ``auto``
(what ``--ray`` without ADDRESS means) joins the cluster ``RAY_ADDRESS`` names, or the one
``ray start`` left on this machine (or the instance this process is connected to);
``HOST:PORT`` (a head node's GCS, port 6379 by default) or ``ray://HOST:PORT`` joins that
cluster. Anything else is refused at once. This module does not import ``ray``.
"""

from __future__ import annotations

import os

from usar_arm.core.job_errors import ClusterUnavailableError

LOCAL = "local"
"""Start a fresh instance here."""
AUTO = "auto"
"""Join the cluster this machine knows of (``--ray`` alone)."""
HELP = ("run the chunks on a Ray cluster: auto (RAY_ADDRESS, or the cluster 'ray start' left on "
        "this machine; the default without ADDRESS), HOST:PORT of a head node, or local (start "
        "a fresh Ray here); needs pip install 'usar-arm[ray]'")
"""What ``--ray ADDRESS`` takes, for the commands' help."""


def host_port(address: str) -> tuple[str, int] | None:
    """(host, port) of an address to probe, or None for ``local`` / an undetectable ``auto``.

    Raises:
        ClusterUnavailableError: not an address of the forms above.
    """
    if address == AUTO:
        address = os.environ.get("RAY_ADDRESS", "") or AUTO
    if address in (AUTO, LOCAL):
        return None
    bare = address.removeprefix("ray://")
    host, _, port = bare.rpartition(":")
    if not host or not port.isdigit():
        raise ClusterUnavailableError(address, "expected local, auto, HOST:PORT or "
                                               "ray://HOST:PORT")
    return host, int(port)


def where(address: str) -> str:
    """The instance an address names, for messages."""
    return "a fresh local Ray instance" if address == LOCAL else f"the Ray cluster at {address}"
