"""Real data: the PSINS vehicle recording's MEMS aided by the FOG-INS position at 1 Hz, through outages.

Independent references: the file's own ``eb0`` and ``db0`` (read here with scipy and turned into FRD
with a matrix written again here), which the filter never sees; and the raw MEMS integrated over each
window from the same state, which the aided run must beat. Skipped with a reason when the data root
is absent.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from conftest import dataset_folder

from sins.aiding import recorded as referenced_aiding
from sins.io.datasets.psins_vehicle import PSINS_VEHICLE_FILE, PSINS_VEHICLE_FOLDER
from sins.io.datasets.root import ENV_VAR

PATH = dataset_folder(PSINS_VEHICLE_FOLDER) / PSINS_VEHICLE_FILE
SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # PSINS right-forward-up → FRD
OUTAGES = ((30.0, 45.0), (60.0, 80.0), (85.0, 95.0))


@pytest.fixture(scope="module")
def aided() -> referenced_aiding.RecordingOutages:
    if not PATH.is_file():
        pytest.skip(f"PSINS vehicle data not found at {PATH}; set {ENV_VAR} to the folder holding it")
    return referenced_aiding.psins_vehicle_outages(OUTAGES)


def test_the_filter_finds_the_files_own_biases(aided):
    mat = scipy.io.loadmat(PATH, squeeze_me=True)
    eb0, db0 = SWAP @ mat["eb0"], SWAP @ mat["db0"]
    gyro = np.degrees(aided.gyro_bias - eb0)
    # Horizontal gyros within 0.001 °/s of eb0 (bias 0.06 °/s): the roll swings and Earth rate show them.
    # The vertical one only through heading, which 100 s of driving north barely changes: 0.01 °/s.
    assert np.all(np.abs(gyro[:2]) < 1e-3) and abs(gyro[2]) < 1e-2, gyro
    # Accelerometers: vertical within 0.005 m/s²; horizontal ones trade against tilt on a straight
    # drive (unobservable apart), 0.02 m/s² (2 mg of the unit's 5 mg).
    accel = aided.accel_bias - db0
    assert abs(accel[2]) < 5e-3 and np.all(np.abs(accel[:2]) < 2e-2), accel


def test_outages_drift_metres_where_the_raw_mems_drifts_tens(aided):
    assert aided.rejected == 0 and aided.rms_m < 1.0
    for window in aided.outages:
        length = window.end_s - window.start_s
        assert window.final_m < 0.1 * length  # under 1.5 m after 15 s, 2 m after 20 s
    # The 15 and 20 s windows: the estimated biases cut the drift to a tenth of the raw MEMS's.
    assert (
        aided.outages[0].final_m < 0.2 * aided.free_m[0] and aided.outages[1].final_m < 0.1 * aided.free_m[1]
    )
    # The filter, tuned to the consumer grade, is cautious on this unit: its 1σ exceeds the error.
    assert all(o.final_m < sigma for o, sigma in zip(aided.outages, aided.predicted_m, strict=True))
