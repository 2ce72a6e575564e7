"""The weather part of the torch open-water env: a plant step in wind and waves with the filter,
and the weather states an episode starts with.

What :class:`usvsim.task.batch.PoleAvoidanceBatch` does in weather, on tensors: the generated
weather step (:func:`usvsim.vessel.torch_plant.load_weather_kernel`, from the CasADi
:func:`usvsim.vessel.weather_plant.build_weather_step` with standard-normal innovations), then
the sensors and the Kalman filter on the true state plus the first-order wave motion the GNSS
position, compass and gyro see (``NavigatedPlant`` with a weather plant); and at an episode's
start the gust and wave motion drawn from their stationary distributions and the wave filter's
prior on the compass (``WeatherPlant.initial_state``). Columns are (N,) tensors, one per state
entry, as in :mod:`usvsim.task.torch_env`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import torch

from usvsim.vessel.torch_plant import TorchWeatherKernel

__all__ = ["compiled_weather_substep", "weather_start_states", "weather_substep"]

Columns = tuple[torch.Tensor, ...]
# the weather states after the closed loop's 13 (usvsim.vessel.weather_plant.WEATHER_STATES):
# gust, wave motion ξ0 and ξ1, then the wave filter's prior (observer.OBSERVER_STATES)
_OBS_PSI, _OBS_R = 3 + 2, 3 + 3  # the prior's ψ and r among them


def weather_substep(
    weather_step: Callable[..., Columns],
    sensed_offsets: Callable[..., Columns],
    nav_step: Callable[..., Columns],
    nx: int,
    s: Columns,
    n: Columns,
    w: Columns,
    g: Columns,
    e_weather: tuple[Any, ...],
    e: tuple[Any, ...],
) -> tuple[Columns, Columns]:
    """One plant step in weather (``weather_step(s, w, g, e_weather)``: ``s`` the closed loop's
    and the weather's states, ``w`` the references, current and the episode's weather inputs),
    then the filter (``nav_step``) on what the sensors see: the true position, heading and yaw
    rate plus the wave motion's offsets (the GNSS velocity is not displaced)."""
    s = weather_step(s, w, g, e_weather)
    d = sensed_offsets(s, w)
    sensed = (s[0] + d[0], s[1] + d[1], s[2] + d[2], s[3], s[4], s[5] + d[3], *s[6:nx])
    return s, nav_step(n, sensed, e)


@functools.cache
def compiled_weather_substep(backend: str = "inductor") -> Callable[..., tuple[Columns, Columns]]:
    """:func:`weather_substep` through ``torch.compile`` (shape-generic, its inputs stacked
    so that one graph serves every plant step, as :func:`usvsim.task.torch_env.compiled_substep`),
    made once per backend. Same arguments and results."""
    from usvsim.task.torch_env import stack_columns

    compiled = torch.compile(_stacked_weather_substep, dynamic=True, backend=backend)

    def substep(
        weather_step: Callable[..., Columns], sensed_offsets: Callable[..., Columns],
        nav_step: Callable[..., Columns], nx: int, s: Columns, n: Columns, w: Columns,
        g: Columns, e_weather: tuple[Any, ...], e: tuple[Any, ...],
    ) -> tuple[Columns, Columns]:  # fmt: skip
        ref = s[0]
        s_t, n_t = compiled(weather_step, sensed_offsets, nav_step, nx, stack_columns(s, ref),
                            stack_columns(n, ref), stack_columns(w, ref), g,
                            stack_columns(e_weather, ref), stack_columns(e, ref))  # fmt: skip
        return tuple(s_t.unbind(0)), tuple(n_t.unbind(0))

    return substep


def _stacked_weather_substep(
    weather_step: Callable[..., Columns], sensed_offsets: Callable[..., Columns],
    nav_step: Callable[..., Columns], nx: int, s: torch.Tensor, n: torch.Tensor,
    w: torch.Tensor, g: Columns, e_weather: torch.Tensor, e: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:  # fmt: skip
    s_next, n_next = weather_substep(
        weather_step, sensed_offsets, nav_step, nx, tuple(s.unbind(0)), tuple(n.unbind(0)),
        tuple(w.unbind(0)), g, tuple(e_weather.unbind(0)), tuple(e.unbind(0)),
    )  # fmt: skip
    return torch.stack(s_next), torch.stack(n_next)


def weather_start_states(
    kernel: TorchWeatherKernel,
    x0: torch.Tensor,
    c0: torch.Tensor,
    inputs: torch.Tensor,
    scales: torch.Tensor,
    normals: torch.Tensor,
) -> torch.Tensor:
    """The weather states (NWS, N) of boats starting at plant state ``x0`` (8, N) and controller
    state ``c0`` (5, N) with weather ``inputs`` (33, N): gust and wave motion ``scales`` (N, 3)
    (their stationary standard deviations) times ``normals`` (N, 3), the wave filter's prior at
    the compass heading (true heading plus the wave yaw) and the true yaw rate, the rest zero."""
    m = torch.zeros((kernel.nws, x0.shape[1]), dtype=x0.dtype, device=x0.device)
    m[0:3] = (scales * normals).T
    refs = torch.zeros_like(x0[0:4])  # the sensed offsets read no reference
    s = (*x0.unbind(0), *c0.unbind(0), *m.unbind(0))
    d_psi = kernel.sensed_offsets(s, (*refs.unbind(0), *inputs.unbind(0)))[2]
    m[_OBS_PSI] = x0[2] + d_psi
    m[_OBS_R] = x0[5]
    return m
