"""The navigation block: sensors, the Kalman filter and its compiled twin, plant+filter fusion,
telemetry estimation, geodesy.
"""
