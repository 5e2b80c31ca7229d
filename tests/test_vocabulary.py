"""The effect vocabulary: an effect defined once, here in the test alone, reaches every part of sins that
knows effects (the simulation, IMU files, ``sins effects``, the gap diagnosis, the physics terms); and
each deterministic effect of the library is named in its definition and at most one registry."""

from __future__ import annotations

import ast
import contextlib
import functools
import io
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest
from numpy.typing import NDArray

from sins import gap, imu
from sins.cli import main
from sins.compensation import terms
from sins.core.earth import G0
from sins.core.series import ImuIncrements, ImuRates
from sins.imu import calibration, vocabulary
from sins.imu import spec as imu_spec
from sins.imu.vocabulary import Param, RegressorInputs, Term, TrueInputs, parameter_field, vector_param

Array = NDArray[np.float64]
DPS = np.pi / 180.0


@dataclass(frozen=True)
class CubicScale(vocabulary.Effect):
    """``k3 u_i³``: a scale error growing with the input's square, this test's own effect."""

    k3: Array = parameter_field()  # noqa: RUF009 (a field with metadata, not a shared default)
    kind: ClassVar[str] = "toy_cubic_scale"
    params: ClassVar[dict[str, tuple[Param, ...]]] = {
        "gyro": (vector_param("k3_ppm_per_dps2", "k3", 1e-6 / DPS**2, "ppm/(°/s)²"),),
        "accel": (vector_param("k3_ppm_per_g2", "k3", 1e-6 / G0**2, "ppm/g²"),),
    }
    description: ClassVar[dict[str, str]] = {"gyro": "k3·ω³ (a test's)", "accel": "k3·f³ (a test's)"}
    candidate: ClassVar[str | None] = "regressors"
    term: ClassVar[Term | None] = Term("toy_cubes", 10)

    def error(self, inputs: TrueInputs, u: Array) -> Array:
        """``k3 u³`` on each axis."""
        return self.k3 * u**3

    @classmethod
    def columns(cls, x: RegressorInputs, sensor: str, axis: int) -> Array:
        """``u_i³``."""
        return x.of(sensor)[:, axis : axis + 1] ** 3


@pytest.fixture
def cubic() -> Iterator[type[CubicScale]]:
    vocabulary.register(CubicScale)
    yield CubicScale
    vocabulary.unregister(CubicScale.kind)


def test_a_registered_effect_is_simulated_in_both_forms(cubic):
    """Against the analytic readings: at a constant rate the reading is ``u + k3 u³`` (rate form) and
    its integral over each step (increment form; the stream integrates at two Gauss nodes, exact for a
    constant input): equal to rounding (1e-12 of the error)."""
    k3 = np.array([2e-3, -1e-3, 5e-4])
    omega = np.array([0.5, -0.3, 0.2])
    dt, n = 0.01, 200
    t = np.arange(n + 1) * dt
    ideal = ImuIncrements(
        t=t, dtheta_b=np.tile(omega * dt, (n, 1)), dv_b=np.tile([0.0, 0.0, 9.8 * dt], (n, 1))
    )
    model = imu.ImuModel((CubicScale("gyro", k3=k3),))
    got = model.corrupt_increments(ideal)
    np.testing.assert_allclose(got.dtheta_b - ideal.dtheta_b, np.tile(k3 * omega**3 * dt, (n, 1)), rtol=1e-9)
    np.testing.assert_array_equal(got.dv_b, ideal.dv_b)
    rates = ImuRates(t=t, omega_ib_b=np.tile(omega, (n + 1, 1)), f_ib_b=np.zeros((n + 1, 3)))
    got_rates = model.corrupt_rates(rates)
    np.testing.assert_allclose(got_rates.omega_ib_b - omega, np.tile(k3 * omega**3, (n + 1, 1)), rtol=1e-9)


def test_a_registered_effect_is_read_from_files_and_listed(cubic):
    effect = imu_spec.effect_from_params("accel.toy_cubic_scale", {"k3_ppm_per_g2": 50.0})
    np.testing.assert_allclose(effect.k3, np.full(3, 50e-6 / G0**2), rtol=1e-15)
    with pytest.raises(ValueError, match="k3_ppm_per_g2"):
        imu_spec.effect_from_params("accel.toy_cubic_scale", {"k3_ppm_per_dps2": 1.0})
    assert "gyro.toy_cubic_scale" in imu.effect_names()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["effects"]) == 0
    assert re.search(
        r"^gyro\.toy_cubic_scale +k3·ω³ \(a test's\)\n +k3_ppm_per_dps2 \[ppm/\(°/s\)²\]",
        out.getvalue(),
        re.M,
    )
    assert (
        "toy_cubic_scale" not in imu.effect_names()
        or vocabulary.effect_class("gyro.toy_cubic_scale") is cubic
    )


def test_a_registered_effect_leaves_with_its_registration():
    assert "gyro.toy_cubic_scale" not in imu.effect_names()
    assert "gyro.toy_cubic_scale" not in gap.CANDIDATES
    assert "toy_cubes" not in terms.GROUPS


#: A short rig session (10 s at each position, 5 s at each rate) with a warming chamber, as in test_gap.
RIG = calibration.RigProcedure(
    position_dwell_s=10.0,
    rate_table=calibration.RateTable(dwell_s=5.0),
    temperature=calibration.TemperatureProfile((0.0, 600.0), (10.0, 40.0)),
)


def test_the_gap_diagnosis_offers_and_finds_a_registered_effect(cubic):
    """A tactical unit's baseline plus the test's effect on the gyros (0.02 ppm/(°/s)², 200 ppm at
    100 °/s: the size of the library's typical nonlinearity, times 3, as test_gap's withheld effects):
    the diagnosis offers it as a regressor candidate whose columns are ``ω³`` and finds it first."""
    assert gap.CANDIDATES["gyro.toy_cubic_scale"].kind == "regressors"
    model = imu_spec.draw_unit("tactical", 1).only(*imu.BASELINE)
    model = model.with_effects(CubicScale("gyro", k3=np.array([0.02, -0.02, 0.02]) * 1e-6 / DPS**2))
    data = calibration.simulate_rig(RIG, model, seed=1)
    columns = gap.regressors_of("gyro.toy_cubic_scale", data)
    np.testing.assert_array_equal(np.hstack(columns), data.ref_gyro**3)
    report = gap.diagnose(data)
    assert report.diagnosis[:1] == ["gyro.toy_cubic_scale"]


def test_the_physics_terms_offer_and_choose_a_registered_effect(cubic):
    """Its group joins every channel's (after the library's, by rank), its column is ``u³``, and on
    residuals made of ``u³`` and white noise (a numpy generator; effect 10 times the noise's RMS over
    the input's spread) the held-back selection takes it alone on every channel."""
    assert terms.GROUPS[-1] == "toy_cubes" and "toy_cubes" in terms.groups_of(3)
    rng = np.random.default_rng(3)
    n = 6000
    w, f = rng.uniform(-1, 1, (n, 3)), rng.uniform(-1, 1, (n, 3))
    x = terms.TermInputs(w, f, None)
    np.testing.assert_array_equal(terms.design(("toy_cubes",), 4, x)[:, -1], f[:, 1] ** 3)
    u = np.hstack([w, f])
    targets = 2.0 * u**3 + 0.2 * rng.standard_normal((n, 6))
    block = np.arange(n) // 100
    folds = [(block % 3 != k, targets) for k in range(3)]
    assert terms.choose(x, folds, block, 3.0) == [("toy_cubes",)] * 6


# --------------------------------------------------------------------------- named once

PACKAGE = Path(__file__).resolve().parents[1] / "sins"

#: Bare kinds that are also other vocabularies' words: the seed model's coefficient names in the
#: compensation's files and tables (``bias``, ``g_sensitivity``), and the aided runs' ``bias`` entity.
OTHER_WORDS = {"bias", "g_sensitivity"}


def _strings_and_names(path: Path) -> tuple[tuple[str, ...], frozenset[str]]:
    """The string constants of a module's code (docstrings aside) and the names it uses (imports aside)."""
    return _strings_and_names_of(path.read_text())


# Each effect's case reads every module: each text is parsed once, keyed by the text, not the path (a
# rule's own test rewrites one file).
@functools.cache
def _strings_and_names_of(text: str) -> tuple[tuple[str, ...], frozenset[str]]:
    tree = ast.parse(text)
    docs = {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr)
        and isinstance(node.value, ast.Constant)
        and isinstance(node.value.value, str)
    }
    strings = tuple(
        n.value
        for n in ast.walk(tree)
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docs
    )
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    names |= {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    return strings, frozenset(names)


def _namers(cls: type[vocabulary.Effect], modules: dict[str, Path]) -> list[str]:
    """The modules that name the effect: its class, one of its names ``SENSOR.KIND`` in a string, or
    its bare kind as a string (unless the kind is one of :data:`OTHER_WORDS`)."""
    full = re.compile(rf"\b(?:{'|'.join(cls.sensors)})\.{cls.kind}\b")
    found = []
    for module, path in modules.items():
        strings, names = _strings_and_names(path)
        bare = cls.kind not in OTHER_WORDS and cls.kind in strings
        if cls.__name__ in names or bare or any(full.search(s) for s in strings):
            found.append(module)
    return found


def _modules() -> dict[str, Path]:
    """Every module of ``sins/``, the dataset readers aside (they map a recording's own columns)."""
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if "datasets" not in parts:
            out[".".join(parts)] = path
    return out


@pytest.mark.parametrize(
    "cls", [t for t in imu.effect_types() if t.stage == "deterministic"], ids=lambda t: t.kind
)
def test_each_deterministic_effect_is_named_in_its_definition_and_one_registry_at_most(cls):
    namers = _namers(cls, _modules())
    assert "sins.imu.effects" in namers and len(namers) <= 2, namers


def test_the_naming_count_catches_a_third_module(tmp_path):
    """The count can fail: a module that builds the effect's columns by its name again is found."""
    fake = tmp_path / "fake.py"
    fake.write_text('"""Mentions gyro.scale_nonlinearity in a docstring only."""\n')
    modules = {"sins.imu.effects": PACKAGE / "imu" / "effects.py", "sins.fake": fake}
    assert _namers(imu.ScaleNonlinearity, modules) == ["sins.imu.effects"]
    fake.write_text('COLUMNS = {"gyro.scale_nonlinearity": lambda u: u * u}\n')
    assert _namers(imu.ScaleNonlinearity, modules) == ["sins.imu.effects", "sins.fake"]
    fake.write_text("from sins.imu import ScaleNonlinearity\n\nX = ScaleNonlinearity('gyro')\n")
    assert _namers(imu.ScaleNonlinearity, modules) == ["sins.imu.effects", "sins.fake"]
