"""What the bridge needs to be safe with a real autopilot: readiness, arming, failsafe delivery.

Three pieces, each tested against ``usvsim sitl`` on loopback (``tests/usvsim/mavlink``):

* :class:`VehicleWatch` keeps what the vehicle last said about itself: the SYS_STATUS pre-arm
  bit, the EKF_STATUS_REPORT flags, its mode (HEARTBEAT) and its STATUSTEXT messages.
* :func:`arm_when_ready` waits until the vehicle looks ready (pre-arm bit healthy and, when
  the vehicle streams its EKF state, an absolute horizontal position; a vehicle that reports
  neither within 3 s counts as ready), then arms; a refusal is
  retried every ``retry_s`` with the vehicle's own STATUSTEXT reasons shown, until
  ``timeout_s`` (wall clock), then :class:`usvsim.mavlink.connection.VehicleError`, one line.
  Real ArduPilot (Rover 4.7.0-dev SITL) set the pre-arm bit ~23 s after boot but accepted
  arming only once its EKF used GPS at ~42 s: the bit alone is not enough, hence the retries.
* :func:`deliver_mode` commands a mode (the failsafe action) and repeats the command every
  ``repeat_s`` until the vehicle acknowledges it (COMMAND_ACK accepted, or a HEARTBEAT in that
  mode) or ``deadline_s`` of wall clock has passed; the link stays open meanwhile. A lost link
  (TCP EOF, reset, refused) is reconnected at most ``reconnect_attempts`` times, waiting
  0.5, 1, 2, ... s between attempts (never a busy loop). The result says whether it was
  acknowledged, after how long and how many commands.

The failsafe actions of ``usvsim bridge --failsafe`` and Rover's equivalents:

==========  ==========================================  ======================================
action      what the boat does                          ArduPilot Rover
==========  ==========================================  ======================================
``loiter``  holds its position (default, for boats)     LOITER (5); no FS_ACTION value: Rover's
                                                        own failsafe offers Hold, RTL, SmartRTL
``hold``    motors stop: a boat *drifts*                HOLD (4) = FS_ACTION 2
``rtl``     returns to home, then holds                 RTL (11) = FS_ACTION 1
==========  ==========================================  ======================================

All waits poll the link with a timeout (no sleeps while a link is up), so they react within one
poll to what arrives.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from usvsim.mavlink.connection import LinkError, LinkLostError, VehicleError
from usvsim.mavlink.link import MavlinkLink
from usvsim.mavlink.messages import (
    MAV_RESULT_ACCEPTED,
    CommandAck,
    EkfStatus,
    Heartbeat,
    MavCommand,
    Received,
    RoverMode,
    StatusText,
    SysStatus,
)

__all__ = [
    "FAILSAFE_MODES",
    "Delivery",
    "VehicleWatch",
    "arm_when_ready",
    "deliver_mode",
]

FAILSAFE_MODES = {"loiter": RoverMode.LOITER, "hold": RoverMode.HOLD, "rtl": RoverMode.RTL}
RECONNECT_WAIT_S = (0.5, 1.0, 2.0, 4.0)  # s between reconnect attempts (then 4 s each)
POLL_S = 0.05  # s, the longest a wait blocks before it looks at the clock again
UNREPORTED_WAIT_S = 3.0  # s, how long to wait for a vehicle to report its pre-arm/EKF state


class VehicleWatch:
    """What the target vehicle last reported about itself (module docstring)."""

    def __init__(self, target_system: int) -> None:
        self.target = target_system
        self.prearm_ok: bool | None = None  # None: no SYS_STATUS with the pre-arm bit yet
        self.ekf_ok: bool | None = None  # None: no EKF_STATUS_REPORT yet
        self.ekf_expected = False  # the vehicle accepted to stream EKF_STATUS_REPORT
        self.mode: int | None = None
        self.armed = False
        self.texts: deque[str] = deque(maxlen=20)

    def accepts(self, r: Received) -> bool:
        return r.src_system == self.target and r.src_component == 1

    def update(self, r: Received) -> None:
        """Note what ``r`` says (only packets of the target's autopilot count)."""
        if not self.accepts(r):
            return
        msg = r.message
        if isinstance(msg, SysStatus) and msg.prearm_ok is not None:
            self.prearm_ok = msg.prearm_ok
        elif isinstance(msg, EkfStatus):
            self.ekf_ok = msg.ready_to_arm
        elif isinstance(msg, Heartbeat):
            self.mode, self.armed = msg.custom_mode, msg.armed
        elif isinstance(msg, StatusText):
            self.texts.append(msg.text)

    def ready(self, unknown_ok: bool) -> bool:
        """Pre-arm bit healthy and, if the vehicle streams its EKF state, a position.

        ``unknown_ok``: a vehicle that has not said (yet) counts as ready (after a wait).
        """
        prearm = self.prearm_ok if self.prearm_ok is not None else unknown_ok
        if self.ekf_ok is not None:
            ekf = self.ekf_ok
        else:
            ekf = unknown_ok or not self.ekf_expected
        return prearm and ekf

    def waiting_for(self) -> str:
        parts = []
        if not self.prearm_ok:
            parts.append(
                "pre-arm checks (SYS_STATUS) "
                + ("not reported yet" if self.prearm_ok is None else "not passed")
            )
        if self.ekf_expected and not self.ekf_ok:
            parts.append(
                "EKF "
                + ("not reported yet" if self.ekf_ok is None else "has no absolute position")
                + " (EKF_STATUS_REPORT)"
            )
        return "; ".join(parts) or "nothing"


def _poll(link: MavlinkLink, watch: VehicleWatch, timeout_s: float) -> list[Received]:
    got = link.poll(timeout_s)
    for r in got:
        watch.update(r)
    return got


def wait_ack(
    link: MavlinkLink, watch: VehicleWatch, command: int, timeout_s: float
) -> CommandAck | None:
    """The vehicle's COMMAND_ACK for ``command`` within ``timeout_s`` (wall), else None."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        for r in _poll(link, watch, min(left, POLL_S)):
            msg = r.message
            if watch.accepts(r) and isinstance(msg, CommandAck) and msg.command == command:
                return msg
    return None


def arm_when_ready(
    link: MavlinkLink,
    watch: VehicleWatch,
    timeout_s: float,
    retry_s: float,
    ack_timeout_s: float,
    say: Callable[[str], None],
) -> int:
    """Arm once the vehicle looks ready; retry refusals (module docstring).

    Returns the number of arming commands sent. ``say`` receives one line per event.

    Raises
    ------
    VehicleError
        If the vehicle has not armed within ``timeout_s``; the message gives its last reason.
    """
    start = time.monotonic()
    deadline = start + timeout_s
    attempts, reason, announced = 0, "", False
    while True:
        while time.monotonic() < deadline and not watch.ready(
            time.monotonic() - start > UNREPORTED_WAIT_S
        ):
            if not announced:
                say(f"waiting for the vehicle: {watch.waiting_for()}")
                announced = True
            _poll(link, watch, POLL_S)
        watch.texts.clear()
        link.arm(watch.target)
        attempts += 1
        ack = wait_ack(link, watch, MavCommand.COMPONENT_ARM_DISARM, ack_timeout_s)
        if ack is not None and ack.result == MAV_RESULT_ACCEPTED:
            say(f"armed (attempt {attempts})")
            return attempts
        _poll(link, watch, POLL_S)  # a STATUSTEXT may follow its ACK
        texts = [t for t in watch.texts if t.lower().startswith(("prearm", "arm"))]
        result = "no COMMAND_ACK" if ack is None else f"COMMAND_ACK result {ack.result}"
        reason = "; ".join(texts) or result
        if time.monotonic() + retry_s > deadline:
            raise VehicleError(
                f"vehicle {watch.target} did not arm within {timeout_s:g} s ({attempts} "
                f"attempts); last reason: {reason}; --arm-timeout-s waits longer"
            )
        say(f"arming refused (attempt {attempts}): {reason}; retrying in {retry_s:g} s")
        until = time.monotonic() + retry_s
        while (left := until - time.monotonic()) > 0:
            _poll(link, watch, min(left, POLL_S))


@dataclass(frozen=True)
class Delivery:
    """How a commanded mode fared: acknowledged or not, after how long, how many commands."""

    mode: RoverMode
    acknowledged: bool
    commands: int
    elapsed_s: float  # wall s from the first command to the acknowledgement (or the deadline)
    how: str  # "COMMAND_ACK", "HEARTBEAT", or why not


def _reconnect(
    link: MavlinkLink, attempt: int, deadline: float, say: Callable[[str], None]
) -> bool:
    """One reconnect attempt after the attempt's wait (cut at ``deadline``); True if it worked."""
    wait = RECONNECT_WAIT_S[min(attempt, len(RECONNECT_WAIT_S) - 1)]
    wait = min(wait, max(0.0, deadline - time.monotonic()))
    time.sleep(wait)  # the link is down: nothing to poll
    try:
        link.reconnect()
    except LinkError as err:
        say(f"reconnect {attempt + 1} failed: {err}")
        return False
    say(f"reconnected (attempt {attempt + 1})")
    return True


def deliver_mode(
    link: MavlinkLink,
    watch: VehicleWatch,
    mode: RoverMode,
    deadline_s: float,
    repeat_s: float,
    reconnect_attempts: int,
    say: Callable[[str], None],
) -> Delivery:
    """Command ``mode`` until acknowledged or ``deadline_s`` (module docstring)."""
    start = time.monotonic()
    deadline = start + deadline_s
    commands, reconnects, why = 0, 0, "no COMMAND_ACK"
    lost = link.lost is not None
    while time.monotonic() < deadline:
        if lost:
            if reconnects >= reconnect_attempts:
                why = f"link lost, {reconnects} reconnect attempts failed"
                break
            lost = not _reconnect(link, reconnects, deadline, say)
            reconnects += 1
            continue
        try:
            link.set_mode(watch.target, mode)
            commands += 1
            next_send = time.monotonic() + repeat_s
            while (left := min(next_send, deadline) - time.monotonic()) > 0:
                for r in _poll(link, watch, min(left, POLL_S)):
                    msg = r.message
                    if not watch.accepts(r):
                        continue
                    if (
                        isinstance(msg, CommandAck)
                        and msg.command == MavCommand.DO_SET_MODE
                        and msg.result == MAV_RESULT_ACCEPTED
                    ):
                        return Delivery(mode, True, commands, time.monotonic() - start, "ACK")
                    if isinstance(msg, Heartbeat) and msg.custom_mode == int(mode):
                        return Delivery(mode, True, commands, time.monotonic() - start, "HB")
        except LinkLostError as err:
            say(f"{err}")
            lost = True
    return Delivery(mode, False, commands, time.monotonic() - start, why)
