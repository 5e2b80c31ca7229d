"""Aided navigation: a tactical unit on 1 Hz GNSS through a 60 s outage, from the truth and from alignment.

Run: ``.venv/bin/python examples/aided_drive.py``. The unit stands still 300 s (its alignment), drives
and turns, then cruises; the receiver, 1 m ahead of and 1.2 m above the IMU, goes silent from 450 to
510 s. The filter knows the grade's noise and bias sizes but not the unit's scale factors,
misalignments or g-sensitivity. The heading for the alignment comes from elsewhere (±1°): a tactical
gyro's 5 °/h bias is too close to the Earth rate's horizontal 10.6 °/h at 45° N to gyrocompass.
"""

import numpy as np

from sins.aiding import alignment, ekf, gnss
from sins.imu import spec
from sins.nav import motion, strapdown, trajectory

d = np.radians
drive = motion.SegmentMotion.from_segments(
    motion.Start(lat=d(45.0), lon=d(7.6), h=250.0, yaw=d(30.0)),
    [motion.Hold(300), motion.Accelerate(10, 15.0, 2.0), motion.Turn(20, d(4.5), 2.0), motion.Hold(300)],
)
truth, ideal = trajectory.generate(drive, 100.0)
readings = spec.draw_unit("tactical", unit_seed=1, run_seed=2).corrupt_increments(ideal, seed=3)
receiver = gnss.GnssConfig(
    rate_hz=1.0, lever_arm_b=np.array([1.0, 0.0, -1.2]), outages=(gnss.Outage(450.0, 510.0),)
)
fixes = gnss.simulate(truth, receiver, seed=4)
config = ekf.FilterConfig.for_grade("tactical")

starts = {
    "truth": ekf.run(readings, fixes, config, strapdown.InitialState.from_series(truth)),
    "alignment": alignment.aligned_run(
        readings, fixes, config, alignment.AlignmentConfig(static_s=300.0), heading=(d(30.7), d(1.0))
    ),
}
end = int(np.searchsorted(truth.t, 510.0)) - 1  # the last sample before the first fix after the outage
print("start      outage end m  predicted 1σ m  final hor m  rejected")
for name, result in starts.items():
    errors = ekf.nav_error_state(result.nav, truth)
    row = int(np.flatnonzero(np.isclose(result.t_cov, 510.0) & ~result.after_update)[0])  # before the fix
    sigma = float(np.hypot(*result.sigma()[row, :2]))
    print(
        f"{name:<10} {np.hypot(*errors[end, :2]):13.2f} {sigma:15.2f} {np.hypot(*errors[-1, :2]):12.2f}"
        f" {result.rejected:9d}"
    )
