"""The MAVLink commands: ``usvsim sitl``, ``usvsim sitl-physics`` and ``usvsim bridge``.

Each runner takes its command's options dataclass (defined beside the code it configures) and
returns the process exit code.
"""

from __future__ import annotations

import dataclasses
import math
import socket
import time

from usvsim.helm.registry import make_helmsman
from usvsim.mavlink.bridge import Bridge, BridgeArgs
from usvsim.mavlink.mission import load_mission
from usvsim.mavlink.sitl import RoverSitl, SitlArgs
from usvsim.mavlink.sitl_physics import JsonPhysics, SitlPhysicsArgs, serve
from usvsim.task.batch import parse_action_kind
from usvsim.task.observations import parse_observation_kind
from usvsim.vessel.vessels import get_vessel

__all__ = ["run_bridge", "run_sitl", "run_sitl_physics"]


def run_sitl(args: SitlArgs) -> int:
    """``usvsim sitl``: serve until Ctrl-C (or ``--duration-s``)."""
    sitl = RoverSitl(args)
    where = args.listen
    print(
        f"usvsim sitl: Rover boat (sysid {args.system_id}) on {where}, speedup "
        f"{args.speedup:g}; connect with: usvsim bridge --connect "
        f"{where.replace('tcpin:', 'tcp:').replace('udpin:', 'udpout:')}",
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
    """``usvsim sitl-physics``: bind, then serve ArduPilot SITL until Ctrl-C."""
    physics = JsonPhysics(
        get_vessel(args.vessel),
        math.radians(args.heading_deg),
        args.steering_channel,
        args.throttle_channel,
    )
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((args.bind, args.port))
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


def run_bridge(args: BridgeArgs) -> int:
    """``usvsim bridge``: exit 0 when the goal is reached, 1 on a failsafe, 130 on Ctrl-C."""
    if not args.mission:
        raise SystemExit("usvsim bridge: --mission FILE is required")
    try:
        mission = load_mission(args.mission)
        helmsman = make_helmsman(args.helmsman, args.action)
        # a trained policy or baseline declares the observation and action it was made for
        args = dataclasses.replace(
            args,
            observation=parse_observation_kind(getattr(helmsman, "observation", args.observation)),
            action=parse_action_kind(getattr(helmsman, "action", args.action)),
        )
    except ValueError as err:
        raise SystemExit(f"usvsim bridge: {err}") from None
    bridge = Bridge(args, mission, helmsman)
    try:
        result = bridge.run()
    except KeyboardInterrupt:
        print("usvsim bridge: interrupted, HOLD commanded", flush=True)
        return 130
    med, p99 = result.latency_summary()
    print(
        f"usvsim bridge: {result.reason}; {result.decisions} decisions; latency median "
        f"{1e3 * med:.2f} ms, p99 {1e3 * p99:.2f} ms; log {args.log_csv}",
        flush=True,
    )
    return 0 if result.reason == "goal reached" else 1
