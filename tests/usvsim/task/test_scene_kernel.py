"""The compiled scene slots against the NumPy reference (:mod:`usvsim.task.scene_kernel`)."""

from __future__ import annotations

import numpy as np
import pytest

from usvsim.task.observations import SCENE_K, scene_observation
from usvsim.task.scene_kernel import load_scene_kernel

pytestmark = pytest.mark.skipif(load_scene_kernel() is None, reason="no C compiler")


@pytest.mark.parametrize("j", [0, 1, 5, SCENE_K, 13])
def test_compiled_slots_equal_the_numpy_reference(j: int) -> None:
    """Bit for bit, with empty slots, equal edge distances (the stable order), a disc the boat
    is inside, and a NaN position."""
    rng = np.random.default_rng(j)
    n = 500
    pos = rng.uniform(-100.0, 100.0, (n, 2))
    psi = rng.uniform(-np.pi, np.pi, n)
    vel = rng.normal(0.0, 2.0, (n, 2))
    goal = rng.uniform(-300.0, 300.0, (n, 2))
    centres = rng.uniform(-200.0, 200.0, (n, j, 2))
    radii = rng.uniform(0.5, 25.0, (n, j))
    disc_vel = rng.normal(0.0, 2.0, (n, j, 2)) * (rng.random((n, j, 1)) < 0.5)
    valid = rng.random((n, j)) < 0.7
    if j >= 2:
        centres[:50, 1] = centres[:50, 0]  # the same disc twice: a tie, kept in order
        radii[:50, 1] = radii[:50, 0]
        centres[60, 0] = pos[60]  # inside a disc: a negative edge distance
    pos[70] = np.nan
    args = (pos, psi, vel, goal, centres, radii, disc_vel, valid)
    ref = scene_observation(*args, backend="numpy")
    got = scene_observation(*args, backend="compiled")
    assert ref.dtype == got.dtype == np.float32 and ref.shape == got.shape == (n, 4 + 6 * SCENE_K)
    np.testing.assert_array_equal(ref.view(np.uint32), got.view(np.uint32))  # -0.0, NaN alike
