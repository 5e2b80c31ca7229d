"""Library walkthrough: simulate a drive, corrupt it with a tactical unit, compensate, integrate, plot.

Run: ``.venv/bin/python examples/library_walkthrough.py [drift.png]``. The page that explains each step is
``docs/guide/library.md``. A 3-minute car drive is simulated exactly; a tactical unit (its seed model's
effects: biases, scale factors, misalignments, g-sensitivity, noise) reads it; the unit's seed model is
fitted by least squares on a simulated rig session of the same unit (another power-on); the readings are
integrated raw and corrected, and the horizontal position errors are printed and plotted.

It prints, per stream, the mean reading error over the drive (gyros °/h, accelerometers mg, against the
exact readings) and the final horizontal error (m), and writes the figure to the path given (default
``drift.png`` in the working folder).
"""

import sys

import numpy as np

import sins
from sins.nav import motion

# 1. Simulate: the truth and the exact IMU readings along a motion (SI units, NED, radians).
d = np.radians
car = motion.SegmentMotion.from_segments(
    motion.Start(lat=d(45.0), lon=d(7.6), h=250.0, yaw=d(30.0)),
    [
        motion.Hold(30),
        motion.Accelerate(20, delta_speed=15.0, ramp=2.0),
        motion.Turn(40, rate=d(4.5), ramp=2.0),
        motion.Hold(30),
        motion.Turn(40, rate=d(-4.5), ramp=2.0),
        motion.Hold(20),
    ],
)
truth, ideal = sins.generate(car, rate_hz=100.0)  # NavSeries, ImuIncrements

# 2. Corrupt: a tactical unit (the seed model's effects only: no temperature to supply) reads the drive.
unit = sins.draw_unit("tactical", unit_seed=7).only(*sins.imu.BASELINE)
readings = unit.corrupt_increments(ideal, seed=3)

# 3. Compensate: the seed model fitted on a rig session of the same unit (another power-on: seed 1).
rig = sins.RigProcedure(positions=26)
strategy = sins.compensation.make("regression").fit(sins.simulate_rig(rig, unit, seed=1))
corrected = strategy.correct_increments(readings)

# 4. Integrate each stream from the true initial state, and compare with the truth.
start = sins.InitialState.from_series(truth)
dt = np.diff(ideal.t)[:, None]
to_units = np.r_[np.full(3, 1.0 / sins.imu.DEG_PER_H), np.full(3, 1.0 / sins.imu.MG)]
errors = {}
print(f"{'stream':<12}" + "".join(f"{c:>10}" for c in sins.imu.CHANNELS) + f"{'final_m':>10}")
for name, stream in {"raw": readings, "regression": corrected}.items():
    reading_error = np.hstack([stream.dtheta_b - ideal.dtheta_b, stream.dv_b - ideal.dv_b]) / dt
    errors[name] = sins.nav_errors(sins.integrate(stream, start), truth)
    final_m = sins.summarize(errors[name]).final_horizontal_m
    row = "".join(f"{v:10.3f}" for v in reading_error.mean(axis=0) * to_units)
    print(f"{name:<12}{row}{final_m:10.2f}")

# 5. Plot: matplotlib, headless; sins.viz.plots.save writes the picture atomically.
import matplotlib.pyplot as plt  # noqa: E402  (only this step needs it)

fig, ax = plt.subplots(figsize=(8, 4))
for name, e in errors.items():
    ax.plot(e.t, e.horizontal_m, label=name)
ax.set(xlabel="time (s)", ylabel="horizontal error (m)", title="tactical unit, 3-minute drive")
ax.legend()
print(f"wrote {sins.viz.plots.save(fig, sys.argv[1] if len(sys.argv) > 1 else 'drift.png')}")
