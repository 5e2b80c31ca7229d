"""Characterise a real IMU: Allan analysis of a recording, the IEEE noise terms, a model file sins simulates.

:mod:`~sins.characterise.allan` computes the overlapping Allan deviation with its confidence intervals;
:mod:`~sins.characterise.terms` fits the IEEE Std 952 / 1293 terms to it; :mod:`~sins.characterise.analysis`
does it for every channel of a recording; :mod:`~sins.characterise.model_file` writes the terms as an IMU
file; :mod:`~sins.characterise.check` simulates that file and overlays its Allan curves on the real ones.
"""

from sins.characterise.allan import AllanCurve
from sins.characterise.analysis import ChannelResult, Characterisation, Residual, characterise, residual
from sins.characterise.terms import TERMS, NoiseFit, Term, fit_terms

__all__ = [
    "TERMS",
    "AllanCurve",
    "ChannelResult",
    "Characterisation",
    "NoiseFit",
    "Residual",
    "Term",
    "characterise",
    "fit_terms",
    "residual",
]
