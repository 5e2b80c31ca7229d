"""The PSINS vehicle recording's MEMS aided by the FOG-INS position at 1 Hz, through 10–30 s outages.

Usage::

    .venv/bin/python tools/aided_psins_vehicle.py [--outage 30 45 --outage 60 80 ...] [--grade consumer]

Prints, per outage, the MEMS's horizontal error against the FOG-INS at the window's end (aided: the
biases the filter estimated before it, fed back), the filter's predicted 1σ there, and the raw MEMS's
error over the same window from the same start; then the final bias estimates beside the file's own
``eb0`` and ``db0`` (turned into FRD). Needs the data root (``SINS_DATA`` or ``../shared/data``).
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.io

from sins.aiding.recorded import psins_vehicle_outages
from sins.io.datasets.psins_vehicle import PSINS_VEHICLE_FILE, PSINS_VEHICLE_FOLDER
from sins.io.datasets.root import dataset_file

#: PSINS right-forward-up into forward-right-down (the reader's turn).
_RFU_TO_FRD = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--outage", nargs=2, type=float, action="append", metavar=("START_S", "END_S"))
    parser.add_argument("--grade", default="consumer")
    parser.add_argument("--rate-hz", type=float, default=1.0)
    args = parser.parse_args()
    windows = (
        tuple((a, b) for a, b in args.outage) if args.outage else ((30.0, 45.0), (60.0, 80.0), (85.0, 95.0))
    )
    result = psins_vehicle_outages(windows, rate_hz=args.rate_hz, grade=args.grade)
    print(
        f"psins_fog_mems_vehicle: MEMS aided by the FOG-INS position at {args.rate_hz:g} Hz "
        f"({result.fixes} fixes, {result.rejected} rejected), filter tuned to {args.grade}; "
        f"horizontal RMS {result.rms_m:.2f} m"
    )
    print(f"{'outage':<12} {'length s':>8} {'aided m':>8} {'pred 1σ m':>10} {'raw MEMS m':>11}")
    for o, sigma, free in zip(result.outages, result.predicted_m, result.free_m, strict=True):
        print(f"{o.start_s:g}-{o.end_s:g} s".ljust(12) + f" {o.end_s - o.start_s:8.0f} {o.final_m:8.2f} "
              f"{sigma:10.2f} {free:11.2f}")  # fmt: skip
    mat = scipy.io.loadmat(dataset_file(PSINS_VEHICLE_FOLDER, PSINS_VEHICLE_FILE), squeeze_me=True)
    print("gyro bias °/s   estimated", np.round(np.degrees(result.gyro_bias), 4),
          " file eb0", np.round(np.degrees(_RFU_TO_FRD @ mat["eb0"]), 4))  # fmt: skip
    print("accel bias m/s² estimated", np.round(result.accel_bias, 4),
          " file db0", np.round(_RFU_TO_FRD @ mat["db0"], 4))  # fmt: skip


if __name__ == "__main__":
    main()
