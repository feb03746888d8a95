"""Where the viewer listens, what to print for it, and which Host headers it answers.

A page served on this machine can be read by any web page the user's browser visits, through
DNS rebinding: a name the attacker controls first resolves to the attacker, then to 127.0.0.1,
and the browser sends the attacker's name as the ``Host`` header. The viewer so answers only
requests whose ``Host`` is an IP address, ``localhost``, or this machine's own name (or a name
given with ``allowed_hosts``); anything else gets 403.

Listening on every interface (``--host 0.0.0.0`` or ``::``) is allowed, with a warning: anyone
who can reach the port can read the trace. The printed address is then one other machines can
use (this machine's address on its default route), not 127.0.0.1.
"""

from __future__ import annotations

import contextlib
import ipaddress
import socket

__all__ = ["host_allowed", "is_loopback", "is_wildcard", "outward_address", "url_for"]

_WILDCARDS = ("0.0.0.0", "::", "")


def is_wildcard(host: str) -> bool:
    """Whether ``host`` means every interface."""
    return host in _WILDCARDS


def is_loopback(host: str) -> bool:
    """Whether ``host`` is reachable from this machine only."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def outward_address() -> str:
    """This machine's address on its default route (no packet is sent), or 127.0.0.1."""
    with contextlib.suppress(OSError), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.connect(("10.255.255.255", 1))  # UDP connect: picks a route, sends nothing
        return str(s.getsockname()[0])
    return "127.0.0.1"


def url_for(host: str, port: int) -> str:
    """``http://HOST:PORT/`` with an IPv6 address in brackets."""
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/"


def _split_host(header: str) -> str:
    header = header.strip().lower()
    if header.startswith("["):  # [v6]:port
        return header[1 : header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


def host_allowed(header: str | None, extra: tuple[str, ...] = ()) -> bool:
    """Whether a request's ``Host`` header names this server (see the module's docstring).

    A request without one (HTTP/1.0, not a browser) is answered.
    """
    if header is None:
        return True
    name = _split_host(header)
    try:
        ipaddress.ip_address(name)
        return True
    except ValueError:
        pass
    names = {"localhost", *(n.lower() for n in extra)}
    with contextlib.suppress(OSError):
        names.update({socket.gethostname().lower(), socket.getfqdn().lower()})
    return name in names or name.endswith(".localhost")
