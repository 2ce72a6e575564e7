"""Environmental forces beyond the steady current: wind with gusts, waves, a heading wave filter.

Pure, vectorised building blocks over N boats (NumPy), seeded per episode, and their CasADi forms
for the compiled plant kernel (:mod:`usvsim.vessel.weather_plant`, issue 38). See
docs/guide/weather.md.

============  =========================================================================
module        contents
============  =========================================================================
``wind``      :class:`Windage` (areas, coefficients), :class:`WindState`, gusts
              (first-order Gauss–Markov), wind forces and yaw moment (Fossen 2021 §10.1)
``waves``     sea-state table, JONSWAP spectrum, first-order wave motion filter, mean drift
``filters``   heading notch wave filter design (Fossen 2021 §13)
``loads``     wind (excess over still air) and wave drift loads as CasADi expressions
``observer``  the Kalman wave filter the weather plant's autopilot uses (Fossen 2021 §13.3)
============  =========================================================================
"""
