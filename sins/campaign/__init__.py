"""Monte-Carlo campaigns: many units × scenarios × strategies, on a laptop or a dask cluster.

:mod:`~sins.campaign.spec` reads a campaign file, :mod:`~sins.campaign.unit` computes one unit's rows
(plain sins), :mod:`~sins.campaign.results` writes them as Parquet and summarises them, and
:mod:`~sins.campaign.engine` (the only module that imports dask) runs the units on a cluster.
"""

from sins.campaign.spec import CampaignSpec, load, nav_seed, rig_seed
from sins.campaign.unit import run_unit, run_units

__all__ = ["CampaignSpec", "load", "nav_seed", "rig_seed", "run_unit", "run_units"]
