"""Pictures: the Rerun viewer bridge (:mod:`~sins.viz.viewer`, the only module that imports rerun) and
headless figures (:mod:`~sins.viz.plots`, the only one that imports matplotlib). Importing this package
imports neither."""

__all__: list[str] = []
