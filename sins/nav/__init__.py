"""Navigation: rotations and the Earth, vehicle motion and its trajectory, the strapdown integrator, and
error metrics. Pure functions over arrays; nothing here knows about IMU errors."""
