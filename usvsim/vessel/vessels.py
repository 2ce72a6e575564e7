"""Vessel parameter registry: frozen dataclasses, one field per coefficient, unit and source each.

Sign convention (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion Control*, 2nd ed.,
ch. 6): hydrodynamic derivatives are written in SNAME notation and are normally negative, so the
added-mass matrix is ``M_A = -[[X_udot, 0, 0], [0, Y_vdot, Y_rdot], [0, N_vdot, N_rdot]]`` and the
damping forces are ``-D(ν)ν = [X_u u + X_|u|u |u|u + X_uuu u³, ...]``.

Actuation is one of two kinds, both with an optional first-order lag (time constants in s):

``forces``   commanded generalised forces ``a = [F_x, F_y]`` (N), ``τ = [F_x, F_y, l_N · F_y]``
             (the form published for the Viknes 830, Loe 2008).
``waterjet`` twin waterjets lumped into one at ``x = x_jet`` (m, negative: aft of the CO):
             ``a = [T, δ]`` with thrust T (N) and nozzle angle δ (rad, positive turns to
             starboard), ``τ = [T cos δ, -T sin δ, -x_jet · T sin δ]``.

Presets: :data:`VIKNES830`, :data:`CYBERSHIP2`, and :data:`DEFAULT_VESSEL` (a Froude-scaled Viknes
830 with waterjets, standing in for the reference study's 10.5 m × 3.5 m twin-waterjet USV).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Literal

__all__ = [
    "CYBERSHIP2",
    "DEFAULT_VESSEL",
    "VESSELS",
    "VIKNES830",
    "Actuation",
    "VesselParams",
    "froude_scale",
    "get_vessel",
]


@dataclass(frozen=True)
class Actuation:
    """Actuator model: kind, limits and first-order lag.

    For ``kind="forces"``: ``a1 = F_x`` (N), ``a2 = F_y`` (N), ``lever_m`` = l_N (m).
    For ``kind="waterjet"``: ``a1 = T`` (N), ``a2 = δ`` (rad), ``lever_m`` = -x_jet (m, > 0).
    ``lag_s`` are the time constants of a1 and a2 (s); 0 means the actuator follows its command
    instantly (no actuator state dynamics).
    """

    kind: Literal["forces", "waterjet"]
    a1_min: float  # N
    a1_max: float  # N
    a2_min: float  # N (forces) or rad (waterjet)
    a2_max: float  # N (forces) or rad (waterjet)
    lever_m: float  # m, yaw lever arm of the lateral force
    lag_s: tuple[float, float] = (0.0, 0.0)  # s, first-order time constants of a1, a2

    def __post_init__(self) -> None:
        _check_finite(self, ("a1_min", "a1_max", "a2_min", "a2_max", "lever_m"))
        if self.kind not in ("forces", "waterjet"):
            raise ValueError(f"Actuation.kind must be 'forces' or 'waterjet', got {self.kind!r}")
        if not self.a1_min < self.a1_max or not self.a2_min < self.a2_max:
            raise ValueError("Actuation limits must satisfy min < max for a1 and a2")
        if self.lever_m <= 0:
            raise ValueError(f"Actuation.lever_m must be > 0 m, got {self.lever_m}")
        if len(self.lag_s) != 2 or any(not math.isfinite(t) or t < 0 for t in self.lag_s):
            raise ValueError(f"Actuation.lag_s must be two finite values >= 0 s, got {self.lag_s}")
        if self.kind == "waterjet" and not (0 < self.a2_max < math.pi / 2):
            raise ValueError("waterjet nozzle limit a2_max must lie in (0, π/2) rad")


@dataclass(frozen=True)
class VesselParams:
    """3-DOF manoeuvring coefficients of one vessel (Fossen 2021, ch. 6).

    Every field is in SI units; derivatives follow SNAME notation (``X_uu`` is X_|u|u, etc.).
    ``xg`` is the x coordinate of the centre of gravity relative to the coordinate origin.
    """

    name: str
    length_m: float  # m, length overall
    beam_m: float  # m
    m: float  # kg, mass
    Iz: float  # kg m², yaw moment of inertia about the CO
    xg: float = 0.0  # m
    # added mass (kg, kg m, kg m²)
    X_udot: float = 0.0
    Y_vdot: float = 0.0
    Y_rdot: float = 0.0
    N_vdot: float = 0.0
    N_rdot: float = 0.0
    # linear damping (N s/m, N s/rad, N m s/m, N m s/rad)
    X_u: float = 0.0
    Y_v: float = 0.0
    Y_r: float = 0.0
    N_v: float = 0.0
    N_r: float = 0.0
    # quadratic (modulus) damping
    X_uu: float = 0.0  # X_|u|u, N s²/m²
    Y_vv: float = 0.0  # Y_|v|v
    Y_rv: float = 0.0  # Y_|r|v
    Y_vr: float = 0.0  # Y_|v|r
    Y_rr: float = 0.0  # Y_|r|r
    N_vv: float = 0.0  # N_|v|v
    N_rv: float = 0.0  # N_|r|v
    N_vr: float = 0.0  # N_|v|r
    N_rr: float = 0.0  # N_|r|r
    # cubic damping
    X_uuu: float = 0.0
    Y_vvv: float = 0.0
    N_rrr: float = 0.0
    actuation: Actuation = field(
        default_factory=lambda: Actuation("forces", -1.0, 1.0, -1.0, 1.0, 1.0)
    )
    notes: str = ""

    def __post_init__(self) -> None:
        numeric = [f.name for f in dataclasses.fields(self) if f.type in ("float", float)]
        _check_finite(self, numeric)
        for name in ("length_m", "beam_m", "m", "Iz"):
            if getattr(self, name) <= 0:
                raise ValueError(f"VesselParams.{name} must be > 0, got {getattr(self, name)}")
        # damping must dissipate energy (Fossen 2021, §6.4): diagonal terms <= 0
        for name in ("X_u", "Y_v", "N_r", "X_uu", "Y_vv", "N_rr", "X_uuu", "Y_vvv", "N_rrr"):
            if getattr(self, name) > 0:
                raise ValueError(
                    f"VesselParams.{name} must be <= 0 (dissipative), got {getattr(self, name)}"
                )
        for name in ("X_udot", "Y_vdot", "N_rdot"):
            if getattr(self, name) > 0:
                raise ValueError(
                    f"VesselParams.{name} must be <= 0 (SNAME added mass), got "
                    f"{getattr(self, name)}"
                )

    @property
    def half_beam_m(self) -> float:
        """Half the beam (m): the boat's radius in collision checks."""
        return 0.5 * self.beam_m


def _check_finite(obj: object, names: list[str] | tuple[str, ...]) -> None:
    for name in names:
        value = getattr(obj, name)
        if not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"{type(obj).__name__}.{name} must be a finite number, got {value!r}")


def froude_scale(base: VesselParams, length_m: float, name: str) -> VesselParams:
    """Scale a vessel geometrically to ``length_m`` with Froude similarity.

    With λ = length_m / base.length_m, Froude scaling keeps U/√(gL) constant, so (Fossen 2021,
    App. D / ITTC 7.5-02-06-01): length λ, speed λ^0.5, time λ^0.5, mass and force λ³, moment λ⁴,
    inertia λ⁵. A coefficient of force per speedⁿ scales as λ^(3 - n/2); moment per speedⁿ as
    λ^(4 - n/2); moment per (rad/s)ⁿ as λ^(4 + n/2); force per (rad/s)ⁿ as λ^(3 + n/2).
    Actuation is not scaled (set it on the result).
    """
    lam = length_m / base.length_m
    if not math.isfinite(lam) or lam <= 0:
        raise ValueError(f"length_m must be a positive finite length, got {length_m}")

    def force_per_speed(n: float) -> float:
        return lam ** (3 - n / 2)

    scaled = {
        "length_m": base.length_m * lam,
        "beam_m": base.beam_m * lam,
        "m": base.m * lam**3,
        "Iz": base.Iz * lam**5,
        "xg": base.xg * lam,
        "X_udot": base.X_udot * lam**3,
        "Y_vdot": base.Y_vdot * lam**3,
        "Y_rdot": base.Y_rdot * lam**4,
        "N_vdot": base.N_vdot * lam**4,
        "N_rdot": base.N_rdot * lam**5,
        "X_u": base.X_u * force_per_speed(1),
        "Y_v": base.Y_v * force_per_speed(1),
        "Y_r": base.Y_r * lam**3.5,
        "N_v": base.N_v * lam**3.5,
        "N_r": base.N_r * lam**4.5,
        "X_uu": base.X_uu * force_per_speed(2),
        "Y_vv": base.Y_vv * force_per_speed(2),
        "Y_rv": base.Y_rv * lam**3,
        "Y_vr": base.Y_vr * lam**3,
        "Y_rr": base.Y_rr * lam**4,
        "N_vv": base.N_vv * lam**3,
        "N_rv": base.N_rv * lam**4,
        "N_vr": base.N_vr * lam**4,
        "N_rr": base.N_rr * lam**5,
        "X_uuu": base.X_uuu * force_per_speed(3),
        "Y_vvv": base.Y_vvv * force_per_speed(3),
        "N_rrr": base.N_rrr * lam**5.5,
    }
    return dataclasses.replace(base, name=name, **scaled)


# --- Viknes 830 -------------------------------------------------------------------------------
# Loe, Ø. A. G. (2008), "Collision avoidance for unmanned surface vehicles", MSc thesis, NTNU,
# Table 2.1/§2.3, as used in NTNU collision-avoidance codes (e.g. Eriksen; Kufoalor). Published
# without added mass (identified jointly into m, Iz) and with τ = [F_x, F_y, 4 m · F_y].
# Known disagreement: N_r = -1281 here; another published variant of the same set uses -3224
# (the value of N_rrr), see the `viknes830_nr3224` preset.
VIKNES830 = VesselParams(
    name="viknes830",
    length_m=8.52,  # m, Viknes 830 LOA (Loe 2008)
    beam_m=2.97,  # m (Loe 2008)
    m=3980.0,  # kg (Loe 2008)
    Iz=19703.0,  # kg m² (Loe 2008)
    X_u=-50.0,  # N s/m (Loe 2008)
    Y_v=-200.0,  # N s/m (Loe 2008)
    N_r=-1281.0,  # N m s/rad (Loe 2008; variant: -3224)
    X_uu=-135.0,  # N s²/m² (Loe 2008)
    Y_vv=-2000.0,  # N s²/m² (Loe 2008)
    N_rrr=-3224.0,  # N m s³/rad³ (Loe 2008)
    actuation=Actuation(
        kind="forces",
        a1_min=-6550.0,  # N (Loe 2008)
        a1_max=13100.0,  # N (Loe 2008)
        a2_min=-645.0,  # N (Loe 2008)
        a2_max=645.0,  # N (Loe 2008)
        lever_m=4.0,  # m, τ_N = 4 F_y (Loe 2008)
        lag_s=(0.0, 0.0),  # published without actuator dynamics
    ),
    notes="Loe (2008). Max yaw moment 2580 N m: cannot turn 10° in 2 s.",
)

VIKNES830_NR3224 = dataclasses.replace(
    VIKNES830, name="viknes830_nr3224", N_r=-3224.0, notes="Loe (2008) variant with N_r = -3224."
)

# --- CyberShip II -------------------------------------------------------------------------------
# Skjetne, Smogeli & Fossen (2004), "A nonlinear ship manoeuvering model: identification and
# adaptive control with experiments for a model ship", Modeling, Identification and Control
# 25(1):3-27, Tables 1, 2 and 4. 1:70 scale model of a supply ship (L = 1.255 m, B = 0.29 m).
# Actuation simplified to generalised forces: |F_x| from the two main propellers' bollard thrust
# T_|n|n n² at the highest tested speed (2 × 3.65e-3 × (2000/60)² ≈ 8.1 N forward, 2 × 5.1e-3 ×
# (2000/60)² × 0.7 ≈ -4 N astern, ASSUMED 70 % astern efficiency); lateral force from rudders and
# bow thruster lumped as ±2 N at the bow-thruster arm 0.466 m (ASSUMED lumping); lag 0.25 s ASSUMED.
CYBERSHIP2 = VesselParams(
    name="cybership2",
    length_m=1.255,  # m (Skjetne et al. 2004)
    beam_m=0.29,  # m (Skjetne et al. 2004)
    m=23.8,  # kg, Table 1
    Iz=1.760,  # kg m², Table 1
    xg=0.046,  # m, Table 1
    X_udot=-2.0,  # Table 1
    Y_vdot=-10.0,  # Table 1
    Y_rdot=0.0,  # Table 1
    N_vdot=0.0,  # Table 1
    N_rdot=-1.0,  # Table 1
    X_u=-0.72253,  # Table 2
    X_uu=-1.32742,  # Table 2
    X_uuu=-5.86643,  # Table 2
    Y_v=-0.88965,  # Table 2
    Y_vv=-36.47287,  # Table 2
    N_v=0.03130,  # Table 2
    N_vv=3.95645,  # Table 2
    Y_rv=-0.805,  # Table 4
    Y_r=-7.250,  # Table 4
    Y_vr=-0.845,  # Table 4
    Y_rr=-3.450,  # Table 4
    N_rv=0.130,  # Table 4
    N_r=-1.900,  # Table 4
    N_vr=0.080,  # Table 4
    N_rr=-0.750,  # Table 4
    actuation=Actuation(
        kind="forces",
        a1_min=-4.0,  # N, ASSUMED astern thrust (see comment above)
        a1_max=8.1,  # N, bollard thrust of two propellers at 2000 rpm (Table 2 thrust coefficient)
        a2_min=-2.0,  # N, ASSUMED lumped lateral force
        a2_max=2.0,  # N, ASSUMED
        lever_m=0.466,  # m, bow thruster x position (Skjetne et al. 2004)
        lag_s=(0.25, 0.25),  # s, ASSUMED
    ),
    notes="Skjetne, Smogeli & Fossen (2004). Another identification of the same ship (Skjetne "
    "2005, PhD thesis) gives Y_v = -0.8612, Y_|v|v = -36.2823, Y_r = 0.1079, N_v = 0.1052.",
)

# --- Default: the study's 10.5 m x 3.5 m twin-waterjet USV ------------------------------------
# No published 3-DOF set exists for it (Vedeler 2019 used the Maritime Robotics "Telemetron"-class
# boat). Derivation, every step an assumption:
#  1. Hull: the Viknes 830 (Loe 2008), the published hull closest in size and type (planing
#     leisure boat used as an NTNU USV), Froude-scaled to L = 10.5 m (λ = 1.232, beam → 3.66 m
#     vs 3.5 m real: within 5 %). Keeps Loe's lumped-added-mass structure.
#  2. Actuation: twin waterjets lumped at x_jet = -4.5 m (jets at the transom, CO at midships,
#     ~0.43 L aft). Total thrust 0..24 kN (Viknes F_x,max 13.1 kN scaled by λ³ ≈ 1.87 → 24.5 kN;
#     no reversing bucket modelled, so thrust ≥ 0), nozzle angle ±30° (typical waterjet steering
#     range, e.g. Hamilton HJ series ±27-30°). First-order lag 0.3 s on thrust (electronically
#     governed engine and impeller spool-up) and 0.15 s on the nozzle (hydraulic steering
#     cylinder), sized so the autopilot meets its step-response requirements. Peak yaw
#     moment is 4.5 × 24e3 × sin 30° = 54 kN m, ~20x the Viknes limit: enough to turn 10° in 2 s.
_VIKNES_SCALED = froude_scale(VIKNES830, 10.5, name="default")
DEFAULT_VESSEL = dataclasses.replace(
    _VIKNES_SCALED,
    beam_m=3.5,  # m, the study's boat (Vedeler 2019); hull coefficients stay Froude-scaled
    actuation=Actuation(
        kind="waterjet",
        a1_min=0.0,  # N, ASSUMED: forward thrust only
        a1_max=24000.0,  # N, ASSUMED: Viknes F_x,max Froude-scaled (λ³)
        a2_min=-math.radians(30.0),  # rad, ASSUMED nozzle limit
        a2_max=math.radians(30.0),  # rad
        lever_m=4.5,  # m, -x_jet, ASSUMED
        lag_s=(0.3, 0.15),  # s, ASSUMED thrust and nozzle lags
    ),
    notes="Viknes 830 (Loe 2008) Froude-scaled to 10.5 m, twin waterjets (assumptions in source).",
)

VESSELS: dict[str, VesselParams] = {
    v.name: v for v in (DEFAULT_VESSEL, VIKNES830, VIKNES830_NR3224, CYBERSHIP2)
}


def get_vessel(name: str) -> VesselParams:
    """Return a preset by name: ``default``, ``viknes830``, ``viknes830_nr3224``, ``cybership2``."""
    try:
        return VESSELS[name]
    except KeyError:
        known = ", ".join(sorted(VESSELS))
        raise ValueError(f"unknown vessel {name!r}; known vessels: {known}") from None
