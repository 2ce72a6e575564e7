"""The MAVLink commands: ``usvsim sitl``, ``usvsim sitl-physics`` and ``usvsim bridge``.

Each runner takes its command's options dataclass (defined beside the code it configures) and
returns the process exit code. User errors (a bad mission, URL, port, key file, a helmsman whose
kinds contradict ``--observation``/``--action``) raise :class:`usvsim.common.errors.UserError`
(or ``OSError``), which :func:`usvsim.cli.main.main` prints as one line with exit status 2.
"""

from __future__ import annotations

import dataclasses
import math
import socket
import time

from usvsim.common.errors import UserError
from usvsim.common.fileio import atomic_write_text, check_writable_file
from usvsim.helm.registry import make_helmsman
from usvsim.mavlink.bridge import Bridge, BridgeArgs
from usvsim.mavlink.connection import check_url
from usvsim.mavlink.mission import load_mission
from usvsim.mavlink.rover_params import shipped_parameter_file
from usvsim.mavlink.sitl import RoverSitl, SitlArgs
from usvsim.mavlink.sitl_physics import JsonPhysics, SitlPhysicsArgs, serve
from usvsim.task.batch import parse_action_kind
from usvsim.task.observations import parse_observation_kind
from usvsim.vessel.vessels import get_vessel

__all__ = ["peer_url", "run_bridge", "run_sitl", "run_sitl_physics"]


# pymavlink's schemes: a listener (tcpin, udpin, and udp, which listens) is reached by
# connecting to it; an endpoint that connects (tcp) or sends (udpout) by listening where it aims
_PEER_SCHEME = {
    "tcpin": "tcp",
    "udpin": "udpout",
    "udp": "udpout",
    "tcp": "tcpin",
    "udpout": "udpin",
}
_ANY_HOST = ("0.0.0.0", "")  # listening on every interface: the peer on this machine uses loopback


def peer_url(url: str, bound_port: int = 0) -> str | None:
    """The MAVLink URL of the other end of an endpoint opened with ``url``; None for serial.

    ``tcpin:H:P`` → ``tcp:H:P``, ``udpin:H:P`` (or ``udp:``) → ``udpout:H:P``: a listener is
    reached at its address (127.0.0.1 for ``0.0.0.0``; ``bound_port``, the port it was given,
    where it asked for port 0). ``tcp:H:P`` → ``tcpin:H:P`` and ``udpout:H:P`` → ``udpin:H:P``:
    an endpoint that connects or sends is reached by listening at the address it aims at.

    >>> peer_url("udpout:127.0.0.1:14550")
    'udpin:127.0.0.1:14550'
    >>> peer_url("tcpin:0.0.0.0:0", bound_port=40123)
    'tcp:127.0.0.1:40123'
    """
    scheme, _, rest = check_url(url).partition(":")
    if scheme not in _PEER_SCHEME:
        return None  # a serial device: the peer is whatever sits on the line's other end
    host, _, port = rest.rpartition(":")
    listens = _PEER_SCHEME[scheme] in ("tcp", "udpout")
    if listens:
        host = "127.0.0.1" if host in _ANY_HOST else host
        port = str(bound_port) if port == "0" and bound_port else port
    return f"{_PEER_SCHEME[scheme]}:{host}:{port}"


def run_sitl(args: SitlArgs) -> int:
    """``usvsim sitl``: serve until Ctrl-C (or ``--duration-s``)."""
    check_url(args.listen)
    try:
        sitl = RoverSitl(args)
    except ValueError as err:  # unknown vessel or autopilot
        raise UserError(str(err)) from None
    bound = sitl.link.local_port if args.listen.endswith(":0") else 0  # the OS chose it
    peer = peer_url(args.listen, bound)
    how = f"usvsim bridge --connect {peer}" if peer else "the bridge on the line's other end"
    print(
        f"usvsim sitl: Rover boat (sysid {args.system_id}) on {args.listen}, speedup "
        f"{args.speedup:g}; connect with: {how}",
        flush=True,
    )
    try:
        sitl.serve()
    except KeyboardInterrupt:
        print("usvsim sitl: stopped", flush=True)
    finally:
        sitl.link.close()
    return 0


def run_sitl_physics(args: SitlPhysicsArgs) -> int:
    """``usvsim sitl-physics``: bind, then serve ArduPilot SITL until Ctrl-C; with
    ``--write-params FILE`` write the vessel's Rover parameter file and exit."""
    try:
        vessel = get_vessel(args.vessel)
    except ValueError as err:
        raise UserError(f"--vessel: {err}") from None
    if args.write_params:
        check_writable_file(args.write_params, "--write-params")
        atomic_write_text(args.write_params, shipped_parameter_file(vessel.name))
        print(
            f"usvsim sitl-physics: Rover parameters for {vessel.name} written to "
            f"{args.write_params}; start ArduPilot with: sim_vehicle.py -v Rover -f motorboat "
            f"--model JSON:{args.bind} --add-param-file={args.write_params}",
            flush=True,
        )
        return 0
    physics = JsonPhysics(vessel, math.radians(args.heading_deg), args.mapping(), args.weather())
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.bind((args.bind, args.port))
    except OSError as err:
        sock.close()
        raise UserError(
            f"cannot listen on udp {args.bind}:{args.port} ({err.strerror}); is another "
            "sitl-physics running? choose another --port or --bind"
        ) from None
    print(
        f"usvsim sitl-physics: {args.vessel} on udp {args.bind}:{sock.getsockname()[1]}; "
        f"start: sim_vehicle.py -v Rover -f motorboat --model JSON:{args.bind}",
        flush=True,
    )
    start = time.monotonic()
    try:
        n = serve(physics, sock, args.duration_s)
    except KeyboardInterrupt:
        n = -1
    finally:
        sock.close()
    if n >= 0:
        print(f"usvsim sitl-physics: {n} frames in {time.monotonic() - start:.1f} s")
    return 0


def _kinds(args: BridgeArgs, helmsman: object) -> BridgeArgs:
    """``args`` with the observation and action kinds the helmsman declares; an explicit
    ``--observation``/``--action`` that contradicts them is refused (not silently replaced)."""
    resolved: dict[str, str] = {}
    for name, default in (("observation", "positional"), ("action", "gaussian")):
        given, declared = getattr(args, name), getattr(helmsman, name, None)
        if given != "auto" and declared is not None and given != declared:
            raise UserError(
                f"--{name} {given} contradicts helmsman {args.helmsman!r}, made for "
                f"{name} {declared}; drop --{name} (default auto: the helmsman's)"
            )
        resolved[name] = declared or (given if given != "auto" else default)
    return dataclasses.replace(
        args,
        observation=parse_observation_kind(resolved["observation"]),
        action=parse_action_kind(resolved["action"]),
    )


def run_bridge(args: BridgeArgs) -> int:
    """``usvsim bridge``: exit 0 when the goal is reached, 1 on a failsafe, 3 when the final
    mode command (the ``--failsafe`` mode) was never acknowledged, 130 on Ctrl-C (the failsafe
    mode commanded first); 2 on a user error, a vehicle that cannot be reached, refuses GUIDED
    (or does not acknowledge it) or does not arm in time (module docstring)."""
    if not args.mission:
        raise UserError("--mission FILE is required (JSON or YAML: poles and goal as lat/lon)")
    check_url(args.connect)
    mission = load_mission(args.mission)
    helmsman = make_helmsman(args.helmsman, "gaussian" if args.action == "auto" else args.action)
    args = _kinds(args, helmsman)
    bridge = Bridge(args, mission, helmsman)
    try:
        result = bridge.run()
    except KeyboardInterrupt:
        fs = bridge.result.failsafe
        state = "acknowledged" if fs is not None and fs.acknowledged else "NOT acknowledged"
        print(f"usvsim bridge: interrupted, {args.failsafe.upper()} commanded ({state})")
        return 130
    med, p99 = result.latency_summary()
    fs = result.failsafe
    ack = "unknown" if fs is None else ("acknowledged" if fs.acknowledged else "NOT acknowledged")
    print(
        f"usvsim bridge: {result.reason}; {args.failsafe.upper()} {ack}; {result.decisions} "
        f"decisions; latency median {1e3 * med:.2f} ms, p99 {1e3 * p99:.2f} ms; "
        f"log {args.log_csv}",
        flush=True,
    )
    return result.exit_status
