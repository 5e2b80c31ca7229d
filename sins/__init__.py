"""sins: a strapdown inertial navigation simulator with learned IMU error correction.

Conventions (stated once, here; every module follows them)
----------------------------------------------------------
Frames
    ``n``  local-level navigation frame, North-East-Down (NED).
    ``b``  body frame, x forward, y right, z down (FRD).
    ``e``  Earth-centred Earth-fixed (ECEF);  ``i``  inertial.
Names
    Quantity first, then frames: ``v_n`` (velocity of the body relative to
    Earth, resolved in n), ``omega_ib_b`` (angular rate of b relative to i,
    resolved in b), ``f_ib_b`` (specific force), ``C_nb`` (direction cosine
    matrix that rotates b-vectors into n: ``x_n = C_nb @ x_b``), ``q_nb``.
    The true or reference quantity carries its frames (``omega_ib_b``,
    ``f_ib_b``, ``omega_dot_b``; a corrected reading is an estimate of it and
    is named so too); a sensor's readings of it are ``gyro`` and ``accel``
    (and their references ``ref_gyro``, ``ref_accel``), the CSV columns' names.
Quaternions
    Scalar-last ``[x, y, z, w]`` (the order of scipy and Rerun), Hamilton
    product, ``q_nb`` represents the same rotation as ``C_nb``.
Euler angles
    ZYX: yaw about down (clockwise from north seen from above), then pitch,
    then roll; ``C_nb = Rz(yaw) @ Ry(pitch) @ Rx(roll)``, the same as
    ``scipy.spatial.transform.Rotation.from_euler("ZYX", [yaw, pitch, roll])``.
Units
    SI and radians everywhere inside the package. Degrees and other units only
    at the edges (scenario files, CSV position/attitude columns, CLI) and such
    names carry a suffix (``lat_deg``, ``yaw_deg``, ``bias_mg``).
Arrays
    Time-major: a series of 3-vectors has shape ``(n, 3)``.
Randomness
    Only through an explicit ``numpy.random.Generator`` or seed passed in.
Earth
    WGS84 ellipsoid, Somigliana normal gravity with the standard height
    correction, Earth rate 7.292115e-5 rad/s; transport rate and Coriolis
    terms are always modelled.
IMU samples
    Increment form: row ``k`` holds the integrals of ``omega_ib_b`` and
    ``f_ib_b`` over ``(t[k-1], t[k]]``. Rate form: instantaneous values at
    ``t[k]``.
"""

from sins.errors import SinsInputError

__version__ = "0.1.0"

__all__ = ["SinsInputError", "__version__"]
