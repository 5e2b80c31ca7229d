"""Library: simulate a short car drive, put a 1 mg bias on one accelerometer, integrate, print the drift.

Run: ``.venv/bin/python examples/library_drift.py``. A 1 mg bias along the body x axis drifts the
position by about ½·b·t² ≈ 0.5 × 9.8e-3 m/s² × (40 s)² ≈ 8 m over the drive's 40 s (Schuler's 84-minute
period makes no difference this early).
"""

import numpy as np

from sins.core.earth import G0
from sins.nav import motion, strapdown, trajectory
from sins.nav.metrics import nav_errors, summarize

d = np.radians
car = motion.SegmentMotion.from_segments(
    motion.Start(lat=d(45.0), lon=d(7.6), h=250.0, yaw=d(30.0)),
    [
        motion.Hold(10),
        motion.Accelerate(10, delta_speed=15.0, ramp=2.0),
        motion.Turn(20, rate=d(4.5), ramp=2.0),
    ],
)
truth, imu = trajectory.generate(car, rate_hz=100.0)  # NavSeries, ImuIncrements (exact)
imu.dv_b[:, 0] += 1e-3 * G0 * np.diff(imu.t)  # a 1 mg bias on the x accelerometer
solution = strapdown.integrate(imu, strapdown.InitialState.from_series(truth))
print(f"final horizontal error {summarize(nav_errors(solution, truth)).final_horizontal_m:.2f} m")
