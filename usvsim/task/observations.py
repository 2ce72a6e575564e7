"""Observations of the pole-avoidance task, built for N boats from the navigation estimate.

Every observation is computed from the *estimated* position and heading (``usvsim.nav.filter``),
never the true state: a policy sees what a real boat's sensors would give it.

==============  ===========================================  =====================================
name            single-boat value                            space
==============  ===========================================  =====================================
``positional``  ``[r_pole, φ_pole, r_goal, φ_goal]``         ``Box((4,), float32)``, raw m and rad
``radar``       image (:mod:`usvsim.task.radar`)             ``Box(0, 255, (1, 50, 119), uint8)``
``radar+goal``  ``{"radar": image, "goal": ĝ}``              ``Dict``; ĝ the standardised goal
``radar+nav``   ``{"radar": image, "goal": ĝ, "nav": n}``   ``Dict``; n = ``[x_N, y_E, ψ, v_N,
                                                             v_E]`` the navigation estimate
``scene``       ``[r_goal, φ_goal, u, v, (r, φ, R, v_x, v_y,  ``Box((52,), float32)``, raw m, rad,
                valid) × 8]``: the goal, the own velocity   m/s (issue 16)
                over ground and the k = 8 nearest obstacles
==============  ===========================================  =====================================

``scene`` (the k-nearest form): ``u, v`` the estimated velocity over ground in the body frame
(forward, starboard); for each of the :data:`SCENE_K` obstacles nearest by edge distance
``r − R``: centre range r, bearing φ, radius R, velocity relative to the own boat (body frame,
m/s) and a validity flag (1 = an obstacle, 0 = an empty slot, all its entries 0). In the pole task
the one pole fills the first slot. The study's 4-vector ``positional`` stays the default.

``radar+nav`` is ``radar+goal`` plus the own navigation estimate in NED (m, m, rad, m/s, m/s,
float32): what a classical radar pipeline (detections → tracks in NED, :mod:`usvsim.nav.tracker`)
needs to place the returns of successive frames in one fixed frame (issue 37).

Ranges in m; bearings in rad relative to the estimated heading, clockwise positive, in [-π, π)
(:func:`usvsim.common.angles.ssa`). The positional observation is left raw (the study's definition);
networks standardise it with :data:`POSITIONAL_STANDARDIZATION`. The goal vector of ``radar+goal``
is standardised inside the observation because it joins the CNN late (study, Sect. "Networks").

Standardisation constants: the mean and standard deviation of a uniform distribution over each
quantity's natural range in the default scenario — r_pole over [0, 100] m (the start range),
r_goal over [0, 220] m (start to goal), bearings over [-π, π) — so ``(x - mean) / std`` is
roughly zero-mean, unit-variance over an episode. Fixed numbers, not fitted to data: a policy's
inputs mean the same thing in every run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, cast, get_args

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from usvsim.common.angles import ssa
from usvsim.task.radar import RadarConfig, UniformSource, render_radar
from usvsim.task.scene_kernel import MAX_SCENE_DISCS, load_scene_kernel

__all__ = [
    "GOAL_STANDARDIZATION",
    "OBSERVATION_KINDS",
    "PERCEPTION",
    "POSITIONAL_STANDARDIZATION",
    "SCENE_FEATURES",
    "SCENE_K",
    "SCENE_STANDARDIZATION",
    "ObservationKind",
    "Standardization",
    "build_observation",
    "nav_vector",
    "observation_space",
    "parse_observation_kind",
    "relative_polar",
    "scene_observation",
    "standardize_scene",
]

ObservationKind = Literal["positional", "radar", "radar+goal", "scene", "radar+nav"]
OBSERVATION_KINDS: tuple[str, ...] = get_args(ObservationKind)
# what a helmsman of each kind perceives of the obstacles: the truth (exact, from the simulator's
# scene) or the radar image; the label of its rows in the bench and stress tables (issue 37)
PERCEPTION: dict[str, str] = {
    "positional": "true nearest",
    "scene": "true scene",
    "radar": "radar image",
    "radar+goal": "radar image",
    "radar+nav": "radar tracks",
}
FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Standardization:
    """``(x - mean) / std`` element-wise over the last axis."""

    mean: tuple[float, ...]
    std: tuple[float, ...]

    def apply(self, x: NDArray[np.floating]) -> NDArray[np.float32]:
        """Standardised ``x`` (..., len(mean)) as float32."""
        return ((x - np.asarray(self.mean)) / np.asarray(self.std)).astype(np.float32)


MAX_RANGE_M = 10_000.0  # m, Box bound on ranges: far beyond any area (an episode ends first)
SCENE_K = 8  # obstacles in the scene observation
SCENE_FEATURES = 6  # per obstacle: r, φ, R, v_x, v_y, valid
MAX_SPEED_MPS = 50.0  # m/s, Box bound on velocities
_BEARING_STD = math.pi / math.sqrt(3.0)  # std of U[-π, π)
GOAL_STANDARDIZATION = Standardization(
    mean=(110.0, 0.0), std=(220.0 / math.sqrt(12.0), _BEARING_STD)
)
POSITIONAL_STANDARDIZATION = Standardization(
    mean=(50.0, 0.0, 110.0, 0.0),
    std=(100.0 / math.sqrt(12.0), _BEARING_STD, 220.0 / math.sqrt(12.0), _BEARING_STD),
)
# scene: the goal as above; u, v over U[-3, 3] m/s·√3 (the study's 3 m/s cruise, sway small);
# per slot r as the pole's range, φ as a bearing, R over [0, 30] m (poles to islets), relative
# velocity over [-6, 6] m/s (two boats at 3 m/s), valid as is. Usvsim's choice, not fitted
_SLOT_MEAN = (50.0, 0.0, 0.0, 0.0, 0.0, 0.0)
_SLOT_STD = (100.0 / math.sqrt(12.0), _BEARING_STD, 30.0 / math.sqrt(12.0), 12.0 / math.sqrt(12.0),
             12.0 / math.sqrt(12.0), 1.0)  # fmt: skip
SCENE_STANDARDIZATION = Standardization(
    mean=(110.0, 0.0, 0.0, 0.0, *_SLOT_MEAN * SCENE_K),
    std=(220.0 / math.sqrt(12.0), _BEARING_STD, 3.0, 3.0, *_SLOT_STD * SCENE_K),
)


def standardize_scene(obs: NDArray[np.floating]) -> NDArray[np.float32]:
    """``scene`` observations (..., 4 + 6 k) under :data:`SCENE_STANDARDIZATION`, every empty
    slot all zeros (so an empty slot never reads as an obstacle at range 0)."""
    x = SCENE_STANDARDIZATION.apply(obs)
    slots = x[..., 4:].reshape(*x.shape[:-1], SCENE_K, SCENE_FEATURES)
    slots *= np.asarray(obs)[..., 4:].reshape(slots.shape)[..., 5:6] > 0.5
    return x


def relative_polar(
    pos_ne: FloatArray, psi_rad: FloatArray, target_ne: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Range (m) and bearing relative to heading (rad, [-π, π)) from ``pos_ne`` to ``target_ne``.

    Shapes: ``pos_ne`` (N, 2), ``psi_rad`` (N,), ``target_ne`` (N, 2) or (N, K, 2) → (N,) or
    (N, K).

    >>> r, b = relative_polar(np.zeros((1, 2)), np.zeros(1), np.array([[0.0, 10.0]]))
    >>> float(r[0]), round(float(np.degrees(b[0])), 6)
    (10.0, 90.0)
    """
    if target_ne.ndim == 3:
        pos_ne, psi_rad = pos_ne[:, None, :], psi_rad[:, None]
    d = target_ne - pos_ne
    return np.hypot(d[..., 0], d[..., 1]), ssa(np.arctan2(d[..., 1], d[..., 0]) - psi_rad)


def parse_observation_kind(kind: object) -> ObservationKind:
    """``kind`` as an :data:`ObservationKind` (e.g. a string read from a file or a flag).

    Raises
    ------
    ValueError
        If ``kind`` is not one of :data:`OBSERVATION_KINDS`.
    """
    if kind not in OBSERVATION_KINDS:
        raise ValueError(f"observation must be one of {OBSERVATION_KINDS}, got {kind!r}")
    return cast(ObservationKind, kind)


def observation_space(kind: ObservationKind, radar: RadarConfig | None = None) -> spaces.Space:
    """The single-boat observation space of ``kind`` (see the module table)."""
    parse_observation_kind(kind)
    radar = radar or RadarConfig()
    image = spaces.Box(0, 255, radar.shape, dtype=np.uint8)
    if kind == "positional":
        high = np.array([MAX_RANGE_M, np.pi, MAX_RANGE_M, np.pi], dtype=np.float32)
        low = np.array([0.0, -np.pi, 0.0, -np.pi], dtype=np.float32)
        return spaces.Box(low, high, dtype=np.float32)
    if kind == "radar":
        return image
    if kind == "scene":
        own_hi = [MAX_RANGE_M, np.pi, MAX_SPEED_MPS, MAX_SPEED_MPS]
        own_lo = [0.0, -np.pi, -MAX_SPEED_MPS, -MAX_SPEED_MPS]
        slot_hi = [MAX_RANGE_M, np.pi, MAX_RANGE_M, 2 * MAX_SPEED_MPS, 2 * MAX_SPEED_MPS, 1.0]
        slot_lo = [0.0, -np.pi, 0.0, -2 * MAX_SPEED_MPS, -2 * MAX_SPEED_MPS, 0.0]
        high = np.array(own_hi + slot_hi * SCENE_K, dtype=np.float32)
        low = np.array(own_lo + slot_lo * SCENE_K, dtype=np.float32)
        return spaces.Box(low, high, dtype=np.float32)
    goal_high = GOAL_STANDARDIZATION.apply(np.array([MAX_RANGE_M, np.pi]))
    goal_low = GOAL_STANDARDIZATION.apply(np.array([0.0, -np.pi]))
    goal = spaces.Box(goal_low, goal_high, dtype=np.float32)
    if kind == "radar+nav":
        nav_hi = np.array([MAX_RANGE_M, MAX_RANGE_M, np.pi, MAX_SPEED_MPS, MAX_SPEED_MPS])
        nav = spaces.Box(-nav_hi.astype(np.float32), nav_hi.astype(np.float32), dtype=np.float32)
        return spaces.Dict({"radar": image, "goal": goal, "nav": nav})
    return spaces.Dict({"radar": image, "goal": goal})


def build_observation(
    kind: ObservationKind,
    pos_ne: FloatArray,
    psi_rad: FloatArray,
    pole_ne: FloatArray,
    goal_ne: FloatArray,
    pole_radius_m: float,
    radar: RadarConfig | None = None,
    noise: UniformSource | None = None,
    velocity_ne: FloatArray | None = None,
) -> NDArray[np.generic] | dict[str, NDArray[np.generic]]:
    """Batched observation of N boats (leading axis N) from their estimated pose.

    ``pos_ne`` (N, 2) m and ``psi_rad`` (N,) rad are the navigation estimate; ``pole_ne`` and
    ``goal_ne`` (N, 2) m; ``velocity_ne`` (N, 2) m/s the estimated velocity over ground (used by
    ``scene`` and ``radar+nav`` only; default 0). Returns an array or, for ``radar+goal`` and
    ``radar+nav``, a dict of arrays.
    """
    parse_observation_kind(kind)
    if kind == "scene":
        n = pos_ne.shape[0]
        vel = np.zeros((n, 2)) if velocity_ne is None else velocity_ne
        return scene_observation(
            pos_ne, psi_rad, vel, goal_ne, pole_ne[:, None, :], np.full((n, 1), pole_radius_m),
            np.zeros((n, 1, 2)), np.ones((n, 1), dtype=bool),
        )  # fmt: skip
    if kind == "positional":
        # pole and goal in one pass: r, b (N, 2) → rows [r_pole, φ_pole, r_goal, φ_goal]
        r, b = relative_polar(pos_ne, psi_rad, np.stack([pole_ne, goal_ne], axis=1))
        obs = np.empty((r.shape[0], 4), dtype=np.float32)
        obs[:, 0::2], obs[:, 1::2] = r, b
        return obs
    r_p, b_p = relative_polar(pos_ne, psi_rad, pole_ne)
    image = render_radar(r_p, b_p, pole_radius_m, radar, noise)
    if kind == "radar":
        return image
    r_g, b_g = relative_polar(pos_ne, psi_rad, goal_ne)
    goal = GOAL_STANDARDIZATION.apply(np.stack([r_g, b_g], axis=-1))
    if kind == "radar+nav":
        return {"radar": image, "goal": goal, "nav": nav_vector(pos_ne, psi_rad, velocity_ne)}
    return {"radar": image, "goal": goal}


def nav_vector(
    pos_ne: FloatArray, psi_rad: FloatArray, velocity_ne: FloatArray | None
) -> NDArray[np.float32]:
    """The ``nav`` entry of ``radar+nav`` (N, 5) float32: ``[x_N, y_E, ψ, v_N, v_E]`` (m, m, rad,
    m/s, m/s) of the navigation estimate; velocity 0 where ``velocity_ne`` is None."""
    vel = np.zeros_like(pos_ne) if velocity_ne is None else velocity_ne
    return np.concatenate([pos_ne, np.asarray(psi_rad)[:, None], vel], axis=1).astype(np.float32)


def scene_observation(
    pos_ne: FloatArray,
    psi_rad: FloatArray,
    velocity_ne: FloatArray,
    goal_ne: FloatArray,
    centres_ne: FloatArray,
    radii_m: FloatArray,
    obstacle_velocity_ne: FloatArray,
    valid: NDArray[np.bool_],
    k: int = SCENE_K,
    backend: Literal["auto", "compiled", "numpy"] = "auto",
) -> NDArray[np.float32]:
    """The ``scene`` observation (N, 4 + 6 k) float32 (module docstring).

    ``pos_ne``, ``velocity_ne``, ``goal_ne`` (N, 2); ``psi_rad`` (N,); ``centres_ne`` (N, J, 2),
    ``radii_m`` (N, J), ``obstacle_velocity_ne`` (N, J, 2) m/s over ground, ``valid`` (N, J).
    Ranges and bearings come from NumPy; the slots (sort, features) from the compiled kernel
    of :mod:`usvsim.task.scene_kernel` where it builds (``backend="auto"``; the same numbers),
    else from NumPy (``"numpy"``, the reference).
    """
    n, j = radii_m.shape
    out = np.zeros((n, 4 + SCENE_FEATURES * k), dtype=np.float32)
    # the goal and every disc in one pass: range and bearing (n, 1 + J)
    r_all, b_all = relative_polar(
        pos_ne, psi_rad, np.concatenate([goal_ne[:, None, :], centres_ne], axis=1)
    )
    c, s = np.cos(psi_rad), np.sin(psi_rad)
    out[:, 0], out[:, 1] = r_all[:, 0], b_all[:, 0]
    numbers = (r_all, b_all, radii_m, obstacle_velocity_ne, velocity_ne, c)
    kernel = load_scene_kernel() if backend != "numpy" else None
    if backend == "compiled" and kernel is None:
        raise ValueError("backend 'compiled': the scene kernel did not build (no C compiler?)")
    if kernel is not None and j <= MAX_SCENE_DISCS and all(a.dtype == np.float64 for a in numbers):
        arrays = [
            np.ascontiguousarray(a)
            for a in (r_all[:, 1:], b_all[:, 1:], radii_m, valid.astype(np.bool_, copy=False),
                      obstacle_velocity_ne, velocity_ne, c, s)
        ]  # fmt: skip
        kernel(n, j, k, *(a.ctypes.data for a in arrays), out.ctypes.data)
        return out

    def body(v: FloatArray) -> tuple[FloatArray, FloatArray]:  # NED → (forward, starboard)
        cc, ss = (c, s) if v.ndim == 2 else (c[:, None], s[:, None])
        return cc * v[..., 0] + ss * v[..., 1], -ss * v[..., 0] + cc * v[..., 1]

    out[:, 2], out[:, 3] = body(velocity_ne)
    if j == 0:
        return out
    r, b = r_all[:, 1:], b_all[:, 1:]
    edge = np.where(valid, r - radii_m, np.inf)
    order = np.argsort(edge, axis=1, kind="stable")[:, :k]
    m = order.shape[1]
    # every disc's features (n J, 6), an empty slot's all zeros, then the k nearest of each
    # boat gathered in one call
    table = np.empty((n * j, SCENE_FEATURES))
    table[:, 0], table[:, 1], table[:, 2] = r.ravel(), b.ravel(), radii_m.ravel()
    vx, vy = body(obstacle_velocity_ne - velocity_ne[:, None, :])
    table[:, 3], table[:, 4] = vx.ravel(), vy.ravel()
    table[:, 5] = valid.ravel()
    table[~valid.ravel()] = 0.0
    feats = table[order + np.arange(0, n * j, j)[:, None]]  # (n, m, 6)
    out[:, 4 : 4 + SCENE_FEATURES * m] = feats.reshape(n, -1)
    return out
