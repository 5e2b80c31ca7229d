"""The EuRoC protocol's commands, unchanged, on a unit that aliases: EuRoC's ADIS16448 read at 100 Hz by
keeping every second reading, with no filter before.

Usage::

    .venv/bin/python tools/aliased_unit.py [--strategies regression ...] [--train NAME ...]
        [--judge NAME ...] [--json OUT.json] [--keep DIR]

A unit sampled below its vibration's frequencies without an anti-alias filter (a phone's, a logger's
that decimates by dropping rows) folds the vibration into slow errors that no model of the sensor holds:
the intervals' residuals grow, and with them the standard errors of every recording's own bias. Each of
EuRoC's eleven sequences is written in the ``.npz`` form into a temporary data root (folder
``euroc_aliased``), every array kept at its even rows (numpy alone, nothing of sins), and the published
split (or ``--train`` and ``--judge``: three and three, as another unit's bar asks) is fitted and judged
by ``tools/euroc_benchmark.py``'s commands. Prints the open-loop table.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import euroc_benchmark


def aliased(source: Path, folder: Path) -> None:
    """The ``.npz`` recording ``source`` written into ``folder`` under its name, every array at its even
    rows: the readings and the reference at half the rate, the readings unfiltered."""
    with np.load(source) as z:
        np.savez(folder / source.name, **{k: np.asarray(z[k])[::2] for k in z.files})


def main(argv: list[str] | None = None) -> int:
    return euroc_benchmark.run_on_euroc_as(
        argv, __doc__.split("\n\n")[0], "euroc_aliased", aliased, ["regression"]
    )


if __name__ == "__main__":
    sys.exit(main())
