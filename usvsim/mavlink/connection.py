"""Connection strings, signing keys and the errors of a MAVLink connection (no pymavlink here).

:class:`LinkError` is a :class:`usvsim.common.errors.UserError`: one line naming the URL or file
and what is allowed or what failed; ``usvsim bridge`` / ``usvsim sitl`` print it and exit 2.
"""

from __future__ import annotations

from pathlib import Path

from usvsim.common.errors import UserError

__all__ = [
    "URL_SCHEMES",
    "HeartbeatTimeoutError",
    "LinkError",
    "LinkLostError",
    "VehicleError",
    "check_url",
    "load_signing_key",
]


class LinkError(UserError, ConnectionError):
    """A MAVLink connection that cannot be made: bad URL, refused, unknown host, no heartbeat."""


class HeartbeatTimeoutError(LinkError, TimeoutError):
    """No vehicle heartbeat within the deadline."""


class LinkLostError(LinkError):
    """An open link that went away: the TCP peer closed (EOF) or reset the connection."""


class VehicleError(LinkError, RuntimeError):
    """The vehicle refused what the session needs (GUIDED, arming within the deadline)."""


URL_SCHEMES = ("tcp", "tcpin", "udp", "udpin", "udpout")


def check_url(url: str) -> str:
    """``url`` if it is a connection string :class:`MavlinkLink` accepts, else :class:`LinkError`.

    Accepted: ``SCHEME:HOST:PORT`` with SCHEME one of :data:`URL_SCHEMES` and PORT in
    0..65535, or a serial device path (``/dev/...`` or ``COMn``, optionally ``,BAUD``).
    """
    if url.startswith("/dev/") or url.upper().startswith("COM"):
        return url
    scheme, _, rest = url.partition(":")
    host, _, port = rest.rpartition(":")
    allowed = f"use SCHEME:HOST:PORT with SCHEME one of {', '.join(URL_SCHEMES)}, or /dev/..."
    if scheme not in URL_SCHEMES or not host or not port.isdigit():
        raise LinkError(f"bad MAVLink URL {url!r}: {allowed}")
    if not 0 <= int(port) <= 65535:
        raise LinkError(f"bad MAVLink URL {url!r}: port {port} is not in 0..65535")
    return url


def load_signing_key(path: str | Path) -> bytes:
    """A 32-byte MAVLink 2 signing key from a file: 32 raw bytes or 64 hex digits.

    The error messages never contain the key material.

    Raises
    ------
    LinkError
        If the file cannot be read or does not hold a key.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as err:
        raise LinkError(f"signing key {path}: cannot read ({err.strerror})") from None
    if len(data) == 32:
        return data
    text = data.strip()
    if len(text) == 64:
        try:
            return bytes.fromhex(text.decode("ascii"))
        except (UnicodeDecodeError, ValueError):
            pass
    raise LinkError(
        f"{path}: a signing key must be 32 raw bytes or 64 hex digits (file has {len(data)} bytes)"
    )
