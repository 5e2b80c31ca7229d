"""A sim-to-real diagnosis: a rig recording of a unit with an effect its model lacks, and what sins gap finds.

Run: ``.venv/bin/python examples/diagnosis.py``. The unit's simulation model is the seed paper's
(bias, scale and misalignment, g-sensitivity, white noise); the "real" unit also has a gyro temperature
bias. The diagnosis fits the model on most of each rig phase, finds where the withheld rows part from
it, and names the effect that closes the gap.
"""

import numpy as np

from sins import gap, imu
from sins.imu import calibration
from sins.imu import spec as imu_spec

rig = calibration.RigProcedure(
    position_dwell_s=10.0,
    rate_table=calibration.RateTable(dwell_s=5.0),
    temperature=calibration.TemperatureProfile((0.0, 600.0), (10.0, 40.0)),
)
unit = imu_spec.draw_unit("tactical", unit_seed=1).only(*imu.BASELINE)
real = unit.with_effects(imu_spec.typical_effect("gyro.temperature_bias", np.random.default_rng(1), 3.0))
report = gap.diagnose(calibration.simulate_rig(rig, real, seed=1))
for line in report.diagnosis:
    print(line)
print("first effect:", report.effects[0].name if report.effects else "none")
