"""Navigation: vehicle motion and its trajectory, the strapdown integrator, and error metrics, on the
rotations and the Earth of the base layer (:mod:`sins.rotation`, :mod:`sins.earth`). Pure functions over
arrays; nothing here knows about IMU errors."""
