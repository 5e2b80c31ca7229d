"""Characterise a real IMU: Allan analysis of a recording, the IEEE noise terms, a model file sins simulates.

:mod:`~sins.characterise.allan` computes the overlapping Allan deviation with its confidence intervals;
:mod:`~sins.characterise.noise_terms` holds the IEEE Std 952 / 1293 terms' Allan variances and spectra;
:mod:`~sins.characterise.fitting` fits them on the log scale and :mod:`~sins.characterise.selection`
decides which the data resolve; :mod:`~sins.characterise.trend` fits a rate ramp to the rate itself;
:mod:`~sins.characterise.still` finds where a unit stood still; :mod:`~sins.characterise.analysis` does it
for every channel of a recording; :mod:`~sins.characterise.reference` takes a reference and the
deterministic errors fitted against it away first; :mod:`~sins.characterise.model_file` writes the terms
as an IMU file; :mod:`~sins.characterise.check` simulates that file and overlays its Allan curves on the
real ones.
"""

from sins.characterise.allan import AllanCurve
from sins.characterise.analysis import (
    ChannelResult,
    Characterisation,
    Residual,
    characterise,
    characterise_channel,
    refit_channel,
    residual,
)
from sins.characterise.noise_terms import TERMS, NoiseFit, Term
from sins.characterise.selection import fit_terms

__all__ = [
    "TERMS",
    "AllanCurve",
    "ChannelResult",
    "Characterisation",
    "NoiseFit",
    "Residual",
    "Term",
    "characterise",
    "characterise_channel",
    "fit_terms",
    "refit_channel",
    "residual",
]
