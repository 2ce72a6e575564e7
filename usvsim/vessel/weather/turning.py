"""The hull's yaw damping in steady turns, for the wave filter's yaw model.

The wave filter (:mod:`usvsim.vessel.weather.observer`) predicts the yaw rate with the
autopilot's design model m ṙ + d r = τ_N + b
(:func:`usvsim.vessel.autopilot.sway_yaw_design_model`), the hull's linearisation about a
straight course. On a straight-line-unstable hull d < 0
(usv105: d = −6.8e3 N m s): in a turn the linear model predicts a rate that runs away while the
real hull, its sway and yaw damping growing with the rate, settles. The filter then explains the
misfit as wave yaw (sea state 4, los-avoid: estimated wave yaw up to 20° where the true one is
about 1°, the low-frequency heading 50° off), and the autopilot steers a wrong heading.

Norrbin's nonlinear yaw model (Fossen 2021, *Handbook of Marine Craft Hydrodynamics and Motion
Control*, 2nd ed., §7.2: T ṙ + H_N(r) = K δ) gives the remedy: the observer predicts with
m ṙ + d r + d₂ r|r| = τ_N + b, d₂ (N m s²/rad²) fitted here to the hull's steady turns (the
quadratic term of Fossen's nonlinear damping, §6.4). Its derivative at r = 0 is zero, so the
observer's steady-state gains, designed about the straight course, do not change.

The fit: the calm closed-loop plant turning steadily with its heading reference held a fixed
offset ahead (0.5°-20°, 60 s); at each steady turn ν̇ = 0, so the actuators' yaw moment equals
the hull's, τ = −(∂ν̇/∂τ)⁻¹ ν̇(ν, τ = 0) from the rigid-body model
(:func:`usvsim.vessel.model.build_force_dynamics`); then d₂ = least squares of τ_N − d r on
r|r|. usv105: d₂ = 2.0e5 N m s²/rad² (the moment within about 10 % at 2-15 °/s).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from usvsim.vessel.plant import Plant

__all__ = ["steady_turn_damping"]

#: heading reference offsets (rad) of the steady turns the fit uses
TURN_OFFSETS_RAD = np.radians(np.linspace(0.5, 20.0, 12))


def steady_turn_damping(plant: Plant, seconds: float = 60.0) -> float:
    """d₂ (N m s²/rad², ≥ 0) of m ṙ + d r + d₂ r|r| = τ_N fitted to ``plant``'s steady turns
    (module docstring), d its design model's damping. 0 when the boats do not turn (r ≈ 0)."""
    n = TURN_OFFSETS_RAD.size
    state = plant.initial_state(np.zeros((n, 3)))
    for _ in range(round(seconds / plant.dt_s)):
        state, _ = plant.step(state, state.x[:, 2] + TURN_OFFSETS_RAD, n_steps=1)
    from usvsim.vessel.model import build_force_dynamics

    f = build_force_dynamics(plant.vessel)
    x, tau = ca.SX.sym("x", 6), ca.SX.sym("tau", 3)
    nu_dot = f(x, tau, ca.DM.zeros(f.size1_in(2)))[3:6]
    jac = ca.Function("turn_balance", [x, tau], [nu_dot, ca.jacobian(nu_dot, tau)])
    r = state.x[:, 5]
    tau_n = np.empty(n)
    for i in range(n):  # 12 boats, once per plant: not a hot path
        rates, gain = (np.asarray(v, dtype=float) for v in jac(state.x[i, :6], np.zeros(3)))
        tau_n[i] = -np.linalg.solve(gain, rates.ravel())[2]
    d = float(plant.design.nomoto.d)
    shape = r * np.abs(r)
    if float(np.sum(shape**2)) < 1e-12:
        return 0.0
    return max(float(np.sum((tau_n - d * r) * shape) / np.sum(shape**2)), 0.0)
