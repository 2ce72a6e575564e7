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

Presets: :data:`USV105` (the default, ``"default"`` is its alias: the reference study's
10.5 m × 3.5 m twin-waterjet USV with a coupled hull from Clarke et al. 1983), :data:`LOE_DEFAULT`
(``"loe-default"``: the default before 2026-12, a Froude-scaled Viknes 830 without sway–yaw
coupling, kept to reproduce earlier results), :data:`VIKNES830`, ``viknes830_nr3224`` and
:data:`CYBERSHIP2`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Literal

__all__ = [
    "CYBERSHIP2",
    "DEFAULT_VESSEL",
    "LOE_DEFAULT",
    "USV105",
    "VESSELS",
    "VESSEL_ALIASES",
    "VIKNES830",
    "Actuation",
    "VesselParams",
    "clarke83_derivatives",
    "froude_scale",
    "get_vessel",
    "vessel_names",
    "without_added_mass_coriolis",
]


@dataclass(frozen=True)
class Actuation:
    """Actuator model: kind, limits and first-order lag.

    For ``kind="forces"``: ``a1 = F_x`` (N), ``a2 = F_y`` (N), ``lever_m`` = l_N (m): the x
    position of the lateral force (negative aft, e.g. rudders).
    For ``kind="waterjet"``: ``a1 = T`` (N), ``a2 = δ`` (rad), ``lever_m`` = -x_jet (m, > 0).
    ``lag_s`` are the time constants of a1 and a2 (s); 0 means the actuator follows its command
    instantly (no actuator state dynamics). ``a2_rate_max`` caps |ȧ2| (a hydraulic steering
    cylinder's slew rate). With a finite ``jet_speed_mps`` V_j, a1 is the thrust at rest
    (bollard) and the thrust delivered at relative surge speed u_r is a1 (1 - u_r / V_j), the
    momentum balance T = ρ Q (V_j - u_r) at constant volume flow Q (Allison 1993, "Marine
    waterjet propulsion", SNAME Trans. 101; constant Q is an assumption). A negative ``a1_min``
    models a reversing bucket (astern thrust); its side force is then reversed with the thrust.
    """

    kind: Literal["forces", "waterjet"]
    a1_min: float  # N
    a1_max: float  # N
    a2_min: float  # N (forces) or rad (waterjet)
    a2_max: float  # N (forces) or rad (waterjet)
    lever_m: float  # m, yaw lever arm of the lateral force
    lag_s: tuple[float, float] = (0.0, 0.0)  # s, first-order time constants of a1, a2
    a2_rate_max: float = math.inf  # a2 units/s, slew-rate limit of a2 (inf: none); needs a lag
    jet_speed_mps: float = math.inf  # m/s, waterjet: thrust falls as T (1 - u_r / V_j) (inf: none)

    def __post_init__(self) -> None:
        _check_finite(self, ("a1_min", "a1_max", "a2_min", "a2_max", "lever_m"))
        if not self.a2_rate_max > 0 or not self.jet_speed_mps > 0:
            raise ValueError("Actuation.a2_rate_max and jet_speed_mps must be > 0 (inf: none)")
        if math.isfinite(self.a2_rate_max) and self.lag_s[1] <= 0:
            raise ValueError("Actuation.a2_rate_max needs a nozzle lag lag_s[1] > 0")
        if math.isfinite(self.jet_speed_mps) and self.kind != "waterjet":
            raise ValueError("Actuation.jet_speed_mps applies to kind='waterjet' only")
        if self.kind not in ("forces", "waterjet"):
            raise ValueError(f"Actuation.kind must be 'forces' or 'waterjet', got {self.kind!r}")
        if not self.a1_min < self.a1_max or not self.a2_min < self.a2_max:
            raise ValueError("Actuation limits must satisfy min < max for a1 and a2")
        if self.lever_m == 0 or (self.kind == "waterjet" and self.lever_m < 0):
            raise ValueError(
                f"Actuation.lever_m must be > 0 m (forces: != 0, < 0 aft), got {self.lever_m}"
            )
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
    draft_m: float = 0.0  # m, draught (0: not given); documents the hull, unused by the model
    cruise_speed_mps: float = 3.0  # m/s, the speed the vessel is designed and tested at
    # > 0: the linear sway/yaw derivatives Y_v, Y_r, N_v, N_r are the values at this speed and
    # scale with the relative speed U_r = |ν_r[0:2]| (the prime system of Clarke et al. 1983 and
    # Fossen 2021 App. D: Y_v = ½ρL²U Y_v'); 0: constant (the published presets)
    linear_ref_speed_mps: float = 0.0
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
        for name in ("length_m", "beam_m", "m", "Iz", "cruise_speed_mps"):
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

        if self.linear_ref_speed_mps < 0 or self.draft_m < 0:
            raise ValueError("VesselParams.linear_ref_speed_mps and draft_m must be >= 0")

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
# (2000/60)² × 0.7 ≈ -4 N astern, ASSUMED 70 % astern efficiency); lateral force of the two
# rudders lumped as ±2 N at the stern, x = -0.5 m (ASSUMED; at speed the bow thruster is
# ineffective). Lumped at the bow thruster (x = +0.466 m) instead, r / τ_N has a right-half-plane
# zero (+0.24 /s) below the hull's unstable pole (+0.65 /s): no stable controller stabilises that
# loop (parity interlacing). Lags 0.1 s ASSUMED (model-scale servos).
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
        lever_m=-0.5,  # m, ASSUMED rudder x position (aft)
        lag_s=(0.1, 0.1),  # s, ASSUMED
    ),
    cruise_speed_mps=0.5,  # m/s, half its top speed (1.01 m/s at full thrust)
    notes="Skjetne, Smogeli & Fossen (2004). Another identification of the same ship (Skjetne "
    "2005, PhD thesis) gives Y_v = -0.8612, Y_|v|v = -36.2823, Y_r = 0.1079, N_v = 0.1052.",
)

# --- loe-default: the default hull until 2026-12 (Loe-derived, uncoupled) ----------------------
# Kept to reproduce results made before the coupled usv105 hull became the default. Its sway-yaw
# model is not physical at full helm (hull audit: 0.06 L turning radius, drift angle -104°).
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
_VIKNES_SCALED = froude_scale(VIKNES830, 10.5, name="loe-default")
LOE_DEFAULT = dataclasses.replace(
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
    notes="The default until 2026-12: Viknes 830 (Loe 2008) Froude-scaled to 10.5 m, twin "
    "waterjets, no sway-yaw coupling (assumptions in source).",
)


def clarke83_derivatives(
    length_m: float, beam_m: float, draft_m: float, block_coefficient: float, speed_mps: float
) -> dict[str, float]:
    """Linear sway–yaw added mass and damping of Clarke, Gedling & Hine (1983), dimensional.

    The regressions as Fossen's ``clarke83`` implements them (MSS / PythonVehicleSimulator,
    ``gnc.py``; Fossen 2021, §7.1 and App. D prime system I): with S = π (T/L)²,
    Y_v̇' = -S (1 + 0.16 C_b B/T - 5.1 (B/L)²), Y_ṙ' = -S (0.67 B/L - 0.0033 (B/T)²),
    N_v̇' = -S (1.1 B/L - 0.041 B/T), N_ṙ' = -S (1/12 + 0.017 C_b B/T - 0.33 B/L),
    Y_v' = -S (1 + 0.4 C_b B/T), Y_r' = -S (-1/2 + 2.2 B/L - 0.08 B/T),
    N_v' = -S (1/2 + 2.4 T/L), N_r' = -S (1/4 + 0.039 B/T - 0.56 B/L); made dimensional with
    ½ρL³, ½ρL⁴, ½ρL⁵ (accelerations) and ½ρL²U, ½ρL³U, ½ρL⁴U (velocities), ρ = 1025 kg/m³.

    The velocity derivatives are the measured hydrodynamic totals: they contain the linearised
    added-mass Coriolis terms (Munk moment), which :mod:`usvsim.vessel.model` adds itself; see
    :func:`without_added_mass_coriolis`.
    """
    rho = 1025.0  # kg/m³, sea water (as clarke83)
    L, B, T, Cb, U = length_m, beam_m, draft_m, block_coefficient, speed_mps
    S = math.pi * (T / L) ** 2
    q = 0.5 * rho
    return {
        "Y_vdot": -S * (1 + 0.16 * Cb * B / T - 5.1 * (B / L) ** 2) * q * L**3,
        "Y_rdot": -S * (0.67 * B / L - 0.0033 * (B / T) ** 2) * q * L**4,
        "N_vdot": -S * (1.1 * B / L - 0.041 * B / T) * q * L**4,
        "N_rdot": -S * (1 / 12 + 0.017 * Cb * B / T - 0.33 * B / L) * q * L**5,
        "Y_v": -S * (1 + 0.4 * Cb * B / T) * q * L**2 * U,
        "Y_r": -S * (-1 / 2 + 2.2 * B / L - 0.08 * B / T) * q * L**3 * U,
        "N_v": -S * (1 / 2 + 2.4 * T / L) * q * L**3 * U,
        "N_r": -S * (1 / 4 + 0.039 * B / T - 0.56 * B / L) * q * L**4 * U,
    }


def without_added_mass_coriolis(
    totals: dict[str, float], X_udot: float, speed_mps: float
) -> dict[str, float]:
    """Remove the linearised C_A(ν)ν at u = U from measured linear derivatives (no double count).

    usvsim's model adds C_A(ν_r)ν_r (Fossen 2021, eq. 6.44, with Y_ṙ = N_v̇ symmetrised); at
    ν = [U, v, r] its linear part is sway -X_u̇ U r and yaw (X_u̇ - Y_v̇) U v - ½(Y_ṙ + N_v̇) U r
    (the second is the Munk moment). Captive-model derivatives already contain them, so
    Y_r = Y_r,tot - X_u̇ U, N_v = N_v,tot + (X_u̇ - Y_v̇) U, N_r = N_r,tot - ½(Y_ṙ + N_v̇) U.
    """
    U = speed_mps
    out = dict(totals)
    out["Y_r"] = totals["Y_r"] - X_udot * U
    out["N_v"] = totals["N_v"] + (X_udot - totals["Y_vdot"]) * U
    out["N_r"] = totals["N_r"] - 0.5 * (totals["Y_rdot"] + totals["N_vdot"]) * U
    return out


# --- usv105: the study's 10.5 m x 3.5 m twin-waterjet USV with a coupled hull --------------------
# A credible order of magnitude, not an identified model (hull audit, 2026-12-01):
#  * hull L = 10.5 m, B = 3.5 m (Vedeler 2019), T = 0.55 m and C_b = 0.36 ASSUMED (ρLBTC_b =
#    7458 kg, loe-default's mass); m and I_z as loe-default (Froude-scaled Viknes 830).
#  * X_u̇ = -0.1 m (clarke83's surge added mass); sway–yaw added mass and linear damping from
#    Clarke, Gedling & Hine (1983) at U = 3 m/s, their added-mass Coriolis part removed (the
#    model adds it), scaled with speed (linear_ref_speed_mps). OUTSIDE THE REGRESSION'S RANGE:
#    B/T = 6.4 and L/B = 3.0 (Clarke's hulls are slender merchant ships) and C_b = 0.36.
#  * cross-flow drag: Fossen (2021) §6.7 strip integral Y = -½ρT ∫ C_D |v + x r|(v + x r) dx,
#    N = -½ρT ∫ x C_D |v + x r|(v + x r) dx with Hoerner's 2-D C_D = 0.586 at B/(2T) = 3.2,
#    fitted to the model's |·|· terms over the turning range (hull audit; 7-9 % residual). Without
#    it the hard-over turn is a 0.26 L pirouette: the term is essential.
#  * surge damping: loe-default's (Froude-scaled Loe 2008).
_USV105_SPEED = 3.0  # m/s, speed of the Clarke derivatives
_USV105_M = _VIKNES_SCALED.m  # kg, 7449 (as loe-default)
_USV105_XUDOT = -0.1 * _USV105_M  # kg, clarke83
_USV105_LINEAR = without_added_mass_coriolis(
    clarke83_derivatives(10.5, 3.5, 0.55, 0.36, _USV105_SPEED), _USV105_XUDOT, _USV105_SPEED
)
USV105 = dataclasses.replace(
    _VIKNES_SCALED,
    name="usv105",
    beam_m=3.5,  # m (Vedeler 2019)
    draft_m=0.55,  # m, ASSUMED (C_b = 0.36 then gives loe-default's mass)
    cruise_speed_mps=3.0,  # m/s, the task's speed
    linear_ref_speed_mps=_USV105_SPEED,
    X_udot=_USV105_XUDOT,  # kg, -745
    Y_vdot=_USV105_LINEAR["Y_vdot"],  # kg, -4.09e3 (Clarke 1983)
    Y_rdot=_USV105_LINEAR["Y_rdot"],  # kg m, -4.82e3 (Clarke 1983)
    N_vdot=_USV105_LINEAR["N_vdot"],  # kg m, -5.68e3 (Clarke 1983)
    N_rdot=_USV105_LINEAR["N_rdot"],  # kg m², -6.90e3 (Clarke 1983)
    Y_v=_USV105_LINEAR["Y_v"],  # N s/m, -2.80e3 at 3 m/s (Clarke 1983)
    Y_r=_USV105_LINEAR["Y_r"],  # N s/rad, +6.47e3 at 3 m/s (Clarke 1983 less C_A)
    N_v=_USV105_LINEAR["N_v"],  # N s, +4.3e2 at 3 m/s (Clarke 1983 less the Munk moment)
    N_r=_USV105_LINEAR["N_r"],  # N m s/rad, -3.44e4 at 3 m/s (Clarke 1983 less C_A)
    Y_vv=-1325.0,  # N s²/m², cross-flow fit (hull audit)
    Y_rv=-6057.0,  # N s²/rad, cross-flow fit (hull audit)
    N_vr=-19813.0,  # N s², cross-flow fit (hull audit)
    N_rr=-46976.0,  # N m s²/rad², cross-flow fit (hull audit)
    N_rrr=0.0,  # the Loe cubic yaw term is replaced by the cross-flow drag
    actuation=Actuation(
        kind="waterjet",
        a1_min=-0.4 * 24000.0,  # N, reversing bucket, ASSUMED 40 % of ahead thrust
        a1_max=24000.0,  # N, bollard thrust, ASSUMED as loe-default's maximum
        # rad, ASSUMED nozzle limit, the low end of the usual ±27-30° (with ±30° the steady
        # hard-over radius is 0.96 L instead of 1.11 L at 3 m/s)
        a2_min=-math.radians(27.0),
        a2_max=math.radians(27.0),  # rad
        lever_m=4.5,  # m, -x_jet, ASSUMED (as loe-default)
        lag_s=(0.3, 0.15),  # s, ASSUMED (as loe-default)
        a2_rate_max=math.radians(60.0),  # rad/s, ASSUMED slew rate (lock to lock in 1 s)
        jet_speed_mps=20.0,  # m/s, ASSUMED jet speed (V_j/u ≈ 2 at 10 m/s)
    ),
    notes="Clarke et al. (1983) linear derivatives and cross-flow drag on the study's 10.5 m x "
    "3.5 m hull, waterjets with slew-rate limit, thrust loss and reversing bucket (all in source).",
)

DEFAULT_VESSEL = USV105  # the coupled hull; "default" names it (VESSEL_ALIASES)

VESSELS: dict[str, VesselParams] = {
    v.name: v for v in (USV105, LOE_DEFAULT, VIKNES830, VIKNES830_NR3224, CYBERSHIP2)
}
VESSEL_ALIASES: dict[str, str] = {"default": USV105.name}


def vessel_names() -> list[str]:
    """Every name :func:`get_vessel` accepts: the aliases first, then the presets, sorted."""
    return [*sorted(VESSEL_ALIASES), *sorted(VESSELS)]


def get_vessel(name: str) -> VesselParams:
    """Return a preset by name: ``default`` (= ``usv105``), ``usv105``, ``loe-default``,
    ``viknes830``, ``viknes830_nr3224``, ``cybership2``."""
    try:
        return VESSELS[VESSEL_ALIASES.get(name, name)]
    except KeyError:
        known = ", ".join(vessel_names())
        raise ValueError(f"unknown vessel {name!r}; known vessels: {known}") from None
