"""``usvsim sitl`` prints how to connect the bridge, and that URL reaches the vehicle.

A listener (``tcpin:``, ``udpin:``) is reached by connecting to it; a SITL that sends
(``udpout:``) is reached by listening where it sends (``udpin:``), not by a second ``udpout:``.
"""

from __future__ import annotations

import re

import pytest

from usvsim.cli import main
from usvsim.cli.mavlink import peer_url
from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import Heartbeat
from usvsim.mavlink.sitl import RoverSitl, SitlArgs

# an endpoint thread that dies of an exception is a failure, not a warning
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")


@pytest.mark.parametrize(
    ("url", "bound", "peer"),
    [
        ("tcpin:127.0.0.1:5760", 0, "tcp:127.0.0.1:5760"),
        ("tcpin:0.0.0.0:5760", 0, "tcp:127.0.0.1:5760"),
        ("tcpin:127.0.0.1:0", 40123, "tcp:127.0.0.1:40123"),
        ("udpin:127.0.0.1:14550", 0, "udpout:127.0.0.1:14550"),
        ("udpin:0.0.0.0:0", 40124, "udpout:127.0.0.1:40124"),
        ("udp:127.0.0.1:14550", 0, "udpout:127.0.0.1:14550"),  # pymavlink's udp: listens
        ("udpout:127.0.0.1:14550", 0, "udpin:127.0.0.1:14550"),
        ("udpout:10.0.0.5:14550", 40125, "udpin:10.0.0.5:14550"),  # a sender's port is its aim
        ("tcp:192.168.1.2:5760", 0, "tcpin:192.168.1.2:5760"),
        ("/dev/ttyUSB0,57600", 0, None),
    ],
)
def test_peer_url(url: str, bound: int, peer: str | None) -> None:
    assert peer_url(url, bound) == peer


def test_sitl_sending_with_udpout_hints_udpin_and_the_bridge_hears_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The hint of ``--listen udpout:...`` is ``udpin:`` at the same address, and a link
    opened with it receives the vehicle's heartbeat."""
    bridge = MavlinkLink("udpin:127.0.0.1:0")  # stands where the SITL will send
    try:
        port = bridge.local_port
        listen = f"udpout:127.0.0.1:{port}"
        run = ["sitl", "--listen", listen, "--duration-s", "2", "--speedup", "20"]
        assert main(run) == 0
        out = capsys.readouterr().out
        hint = re.search(r"connect with: usvsim bridge --connect (\S+)", out)
        assert hint is not None, out
        assert hint.group(1) == f"udpin:127.0.0.1:{port}"
        got = bridge.poll(1.0)
        assert [r.src_system for r in got if isinstance(r.message, Heartbeat)][:1] == [1]
    finally:
        bridge.close()


@pytest.mark.parametrize("listen", ["udpin:127.0.0.1:0", "tcpin:127.0.0.1:0"])
def test_the_hint_of_a_listener_reaches_it(listen: str) -> None:
    """For a listener on an OS-chosen port the hint names that port, and a link opened with it
    gets the vehicle's heartbeat."""
    sitl = RoverSitl(SitlArgs(listen=listen, speedup=20.0, ekf_delay_s=0.0))
    with sitl.serving_in_background(30.0):
        url = peer_url(listen, sitl.link.local_port)
        assert url is not None and url.endswith(f":{sitl.link.local_port}")
        assert url.split(":")[0] == {"udpin": "udpout", "tcpin": "tcp"}[listen.split(":")[0]]
        link = MavlinkLink(url)
        try:
            assert link.wait_heartbeat(5.0).src_system == 1
        finally:
            link.close()
