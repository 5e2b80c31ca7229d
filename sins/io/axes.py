"""Body axes named by letters, and the turn from another convention's frames into sins's.

sins's body frame is FRD (x forward, y right, z down) and its navigation frame NED. A recording on other
axes names them with three letters, one per recorded axis x, y, z, each the body direction that axis
points to: ``f``/``b`` (forward, back), ``r``/``l`` (right, left), ``d``/``u`` (down, up). ``frd`` is
sins's own; ``flu`` is ROS's body frame (REP 103: x forward, y left, z up); ``rfu`` the axes of a phone
lying flat and pointing ahead, or of a unit whose axes were named after ENU (x east, y north, z up)
while the vehicle faced north. The frame must be right-handed (x × y = z).

A reading ``v`` on such axes is ``M @ v`` in FRD, with ``M = frame_matrix(axes)``: every element of
``M`` is 0 or ±1, so the conversion only moves and negates numbers and is exact.
"""

from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import NDArray

from sins.errors import SinsInputError

Array = NDArray[np.float64]

#: Each letter's direction in FRD.
DIRECTIONS = {
    "f": (1.0, 0.0, 0.0),
    "b": (-1.0, 0.0, 0.0),
    "r": (0.0, 1.0, 0.0),
    "l": (0.0, -1.0, 0.0),
    "d": (0.0, 0.0, 1.0),
    "u": (0.0, 0.0, -1.0),
}

#: sins's body axes, and ROS's (REP 103).
FRD = "frd"
FLU = "flu"

#: ENU vectors into NED: north = y, east = x, down = -z (a proper rotation, det +1).
ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def frame_matrix(axes: str) -> Array:
    """The (3, 3) matrix ``M`` that turns readings on ``axes`` into FRD: ``v_frd = M @ v``.

    Parameters
    ----------
    axes : three letters from f/b, r/l, d/u, one per recorded axis x, y, z (``"flu"``); case ignored

    Raises
    ------
    SinsInputError
        not three such letters; two axes along one line; a left-handed frame (naming the right-handed
        frames with the same first two axes).
    """
    text = str(axes).strip().lower()
    if len(text) != 3 or any(c not in DIRECTIONS for c in text):
        raise SinsInputError(
            f"frame {axes!r}: expected three letters, one per axis x, y, z, from f/b (forward, back), r/l "
            "(right, left), d/u (down, up), such as frd (sins's own) or flu (ROS)"
        )
    m = np.column_stack([DIRECTIONS[c] for c in text])
    det = float(np.linalg.det(m))
    if abs(det) < 0.5:
        raise SinsInputError(f"frame {axes!r}: two axes lie along one line (each of f/b, r/l, d/u once)")
    if det < 0:
        right = frame_letters(np.column_stack([m[:, 0], m[:, 1], np.cross(m[:, 0], m[:, 1])]))
        raise SinsInputError(f"frame {axes!r} is left-handed (x × y must give z): did you mean {right}?")
    return m


def frame_letters(m: Array) -> str:
    """The letters of a signed permutation matrix ``m`` (``v_frd = m @ v``): :func:`frame_matrix`'s
    inverse."""
    out = []
    for column in np.asarray(m, dtype=float).T:
        letter = next((k for k, d in DIRECTIONS.items() if np.allclose(column, d)), None)
        if letter is None:
            raise ValueError(f"not a signed permutation column: {column}")
        out.append(letter)
    return "".join(out)


def right_handed_frames() -> tuple[str, ...]:
    """Every right-handed frame's letters (24), sins's own first."""
    frames = []
    for x, y in itertools.permutations(DIRECTIONS, 2):
        mx, my = np.array(DIRECTIONS[x]), np.array(DIRECTIONS[y])
        if abs(float(mx @ my)) > 0.5:
            continue
        frames.append(x + y + frame_letters(np.cross(mx, my)[:, None]))
    return tuple(sorted(frames, key=lambda f: f != FRD))


def to_frd(values: Array, m: Array) -> Array:
    """Rows of readings (n, 3) on the axes ``m`` describes, in FRD (exact: moves and sign changes)."""
    out = np.empty_like(values)
    for i in range(3):
        j = int(np.flatnonzero(m[i])[0])
        out[:, i] = values[:, j] if m[i, j] > 0 else -values[:, j]
    return out


__all__ = [
    "DIRECTIONS",
    "ENU_TO_NED",
    "FLU",
    "FRD",
    "frame_letters",
    "frame_matrix",
    "right_handed_frames",
    "to_frd",
]
