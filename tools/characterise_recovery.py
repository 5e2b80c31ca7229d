"""The 20-seed recovery table of the characterise guide: per case and term, how many seeds' statements hold.

Usage::

    .venv/bin/python tools/characterise_recovery.py

Uses the tests' numpy-only generator and cases (``tests/test_characterise.py``). A statement holds when a
resolved term is within 2σ of the truth, or an unresolved term's upper bound is at least the truth
(absent terms have truth 0); the count of seeds where the term was resolved is in brackets.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sins.characterise import analysis, terms
from tests.test_characterise import _KEYS, CASES, DT, N_ROWS, SEEDS, _correct, generate


def main() -> None:
    """Print the table (markdown)."""
    symbols = [terms.SYMBOLS[n] for n in terms.TERMS]
    print("| case | " + " | ".join(symbols) + " |")
    print("|---" * (len(symbols) + 1) + "|")
    for case, process in CASES.items():
        right = {n: 0 for n in terms.TERMS}
        resolved = {n: 0 for n in terms.TERMS}
        for seed in SEEDS:
            x = generate(np.random.default_rng([seed, 23]), N_ROWS, DT, **process)
            fit = analysis.characterise_channel(x, DT).fit
            for key, name in _KEYS.items():
                right[name] += _correct(fit.terms[name], process.get(key, 0.0))
                resolved[name] += fit.terms[name].resolved
        cells = [f"{right[n]} ({resolved[n]})" for n in terms.TERMS]
        print(f"| {case} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
