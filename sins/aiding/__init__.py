"""Aided navigation: a simulated GNSS receiver, the GNSS/INS error-state filter and initial alignment.

``gnss`` simulates and checks fixes; ``ekf`` is the 15-state loosely coupled filter on the strapdown
integrator; ``alignment`` levels, gyrocompasses and hands the filter its start; ``policy`` picks which
alignment starts a run; ``outages`` measures an aided run's error over its outage windows.
"""
