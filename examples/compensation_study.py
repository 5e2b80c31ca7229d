"""A compensation study: fit strategies on one rig session of a unit, judge them on another.

Run: ``.venv/bin/python examples/compensation_study.py``. A tactical unit with a gyro scale
nonlinearity (an error the seed paper's linear model lacks) is calibrated on a 26-position rig with a
rate table; each strategy is fitted on that session and judged on a second session of the same unit
with fresh noise, per channel, as the RMS of reading − reference after correction.
"""

import numpy as np

from sins import compensation, imu
from sins.imu import calibration
from sins.imu import spec as imu_spec

unit = imu_spec.draw_unit("tactical", unit_seed=7).only(*imu.BASELINE)
unit = unit.with_effects(imu.ScaleNonlinearity("gyro", k2=np.array([0.0, 3e-3, 0.0])))  # per rad/s
rig = calibration.RigProcedure(
    positions=26, position_dwell_s=5.0, rate_table=calibration.RateTable(rates_dps=(20.0, 100.0, 200.0))
)
fit_session = calibration.simulate_rig(rig, unit, seed=1)
judge_session = calibration.simulate_rig(rig, unit, seed=2)

print(f"{'strategy':<12}" + "".join(f"{c:>10}" for c in imu.CHANNELS) + "   (RMS after, °/h and mg)")
scale = np.r_[np.full(3, 1 / imu.DEG_PER_H), np.full(3, 1 / imu.MG)]
for name in ("none", "regression", "kohonen"):
    strategy = compensation.make(name).fit(fit_session)
    rms = compensation.residual_rms(strategy, judge_session)
    after = np.array([v["rms_after"] for v in rms.values()]) * scale
    print(f"{name:<12}" + "".join(f"{v:10.2f}" for v in after))
