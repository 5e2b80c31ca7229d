"""`sins characterise`: the Allan analysis, the IEEE terms and their selection, the ramp, the reference
taken away, the model file, the closing check and the refusals.

The test recordings come from ``tests/numpy_noise.py``, numpy alone (not sins's IMU model): white rate
noise, a first-order Gauss–Markov bias, flicker (Kasdin and Walter's fractional difference), a random walk
of the rate, quantization of the angle and a ramp; the exact discrete Allan variances of the classical
processes are written out beside them, independently of :mod:`sins.characterise.noise_terms`. The 20-seed
statistical sweep of issue 32 is ``tools/characterise_recovery.py`` (figures in the guide); the tests
run two seeds of each of its cases.
"""

from __future__ import annotations

import json
import math

import allantools
import numpy as np
import pytest
import scipy.io

from sins import cli, io, scenario
from sins.characterise import analysis, check, model_file, reference, selection, still, trend
from sins.characterise import noise_terms as terms
from sins.characterise.allan import allan, edf_overlapping
from sins.core.series import ImuRates
from sins.errors import SinsInputError
from tests.conftest import dataset_folder, refusal
from tests.numpy_noise import CASES, DT, KEYS, case_series, exact_avar, generate, truths

SEEDS = range(20)
_DEG = math.pi / 180.0


def _coefficients(process: dict[str, float]) -> np.ndarray:
    """The library's squared coefficients (6,) of a generator's process."""
    return np.array([process.get(key, 0.0) for key in KEYS]) ** 2


# --------------------------------------------------------------------------- the Allan deviation


def test_allan_deviation_matches_allantools():
    """Our overlapping deviation is allantools' ``oadev`` of the same rates to 1e-9, at every octave."""
    x = generate(np.random.default_rng(1), 40_000, 0.1, arw=1e-3, sigma_b=2e-4, tau_c=20.0, k=1e-6)
    curve = allan(x, 0.1)
    taus, adev, _, _ = allantools.oadev(x, rate=10.0, data_type="freq", taus=curve.tau_s)
    np.testing.assert_allclose(taus, curve.tau_s)
    np.testing.assert_allclose(curve.adev, adev, rtol=1e-9)


def test_segments_pool_only_their_own_differences():
    """Two segments give the pooled mean of squared differences, none across the gap."""
    x = generate(np.random.default_rng(2), 4000, 0.1, arw=1e-3)
    both = allan(x, 0.1, [(0, 2000), (2000, 4000)])
    a, b = allan(x[:2000], 0.1), allan(x[2000:], 0.1)
    k = len(a.avar)
    pooled = (a.avar * a.terms + b.avar * b.terms) / (a.terms + b.terms)
    np.testing.assert_allclose(both.avar[:k], pooled, rtol=1e-12)


def test_detrended_curve_is_the_curve_of_the_detrended_rate():
    """A curve less a ramp, from its sums alone, is the curve of the rate less that ramp (to rounding),
    over segments with their own offsets; and a pure ramp's curve is ``R²τ²/2`` exactly."""
    rng = np.random.default_rng(3)
    n, dt, ramp = 50_000, 0.1, 2.7e-5
    x = rng.standard_normal(n) + np.cumsum(rng.standard_normal(n)) * 0.01 + 3e-5 * np.arange(n) * dt
    spans = [(0, 20_000), (20_000, 50_000)]
    direct = allan(x - ramp * dt * np.arange(n), dt, spans)
    np.testing.assert_allclose(allan(x, dt, spans).detrended(ramp).avar, direct.avar, rtol=1e-10)
    line = allan(ramp * dt * np.arange(n), dt)
    np.testing.assert_allclose(line.avar, ramp**2 * line.tau_s**2 / 2.0, rtol=1e-9)
    np.testing.assert_allclose(line.detrended(ramp).avar, 0.0, atol=1e-12 * float(line.avar.max()))


def test_edf_agrees_with_nist_and_greenhall():
    """The spectral EDF of each noise type agrees with NIST SP 1065's closed forms to 12 % at every octave,
    and with allantools' Greenhall EDF to 12 % from ``m = 8`` (below, Greenhall's is up to 17 % higher
    than the closed forms; ours is exactly ``2n/3`` at ``m = 1`` for white noise, as NIST's); flicker's
    EDF is Greenhall's to 15 % from ``m = 8`` (NIST's closed form for it is a coarse approximation)."""
    n = 1 << 15
    curve = allan(np.random.default_rng(3).standard_normal(n), 1.0)
    for column, slope, alpha in (
        (terms.N, -1.0, 0),
        (terms.K, 1.0, -2),
        (terms.Q, -2.0, 2),
        (terms.B, 0.0, -1),
    ):
        coefficients = np.zeros(6)
        coefficients[column] = 1.0
        edf, corr = terms.spectral(curve, coefficients, None)
        green = [allantools.edf_greenhall(alpha, 2, int(m), n + 1, overlapping=True) for m in curve.clusters]
        assert np.allclose(np.diag(corr), 1.0)
        if column == terms.B:
            np.testing.assert_allclose(edf[3:-1], np.array(green)[3:-1], rtol=0.15)
            continue
        nist = edf_overlapping(n + 1, curve.clusters, np.full(len(curve.clusters), slope))
        np.testing.assert_allclose(edf, nist, rtol=0.12)
        np.testing.assert_allclose(edf[3:-1], np.array(green)[3:-1], rtol=0.12)


@pytest.mark.parametrize(
    "process",
    [
        dict(arw=1e-3),
        dict(q=2e-4),
        dict(sigma_b=1e-3, tau_c=5.0),
        dict(k=1e-5),
        dict(r=1e-7),
        dict(flicker=1e-3),
    ],
    ids=["white", "quantization", "gauss_markov", "rate_random_walk", "ramp", "flicker"],
)
def test_each_process_has_its_analytic_allan_variance(process):
    """Over 20 seeds, the mean Allan variance of each generated process is its exact discrete one within
    4 standard errors (from the spread across seeds), and the library's IEEE form is within 4 % of it at
    cluster sizes of 4 and more (the random walk's extra ``K² dt / 6m`` and the sampled Gauss–Markov
    bias's ``O(dt/T)`` vanish there). Flicker has no closed form to write out: its mean is the library's
    sampled form (:func:`~sins.characterise.noise_terms.flicker_shape`, ``2B²/π`` at one sample) within 4
    standard errors at every octave."""
    n, dt = 1 << 14, 0.1
    runs = np.array([allan(generate(np.random.default_rng(s), n, dt, **process), dt).avar for s in SEEDS])
    m = allan(np.zeros(n), dt).clusters
    library = terms.model_avar(m * dt, _coefficients(process), process.get("tau_c"), m)
    mean, sem = runs.mean(axis=0), runs.std(axis=0, ddof=1) / math.sqrt(len(runs))
    if "flicker" in process:
        assert library[0] == pytest.approx(2.0 * process["flicker"] ** 2 / math.pi, rel=1e-6)
        assert np.all(np.abs(mean - library) <= 4.0 * sem)
        return
    exact = exact_avar(m, dt, **process)
    assert np.all(np.abs(mean - exact) <= 4.0 * sem + 1e-12 * exact)
    np.testing.assert_allclose(library[m >= 4], exact[m >= 4], rtol=0.04)


def test_confidence_intervals_cover_the_true_deviation():
    """Over 20 seeds of white noise with a Gauss–Markov bias, the 95 % intervals (EDF from the fitted
    noise) hold the exact Allan deviation at 90-99 % of the points."""
    process = dict(arw=1e-3, sigma_b=3e-4, tau_c=20.0)
    held = total = 0
    for seed in SEEDS:
        x = generate(np.random.default_rng([seed, 11]), 1 << 15, 0.1, **process)
        raw = allan(x, 0.1)
        curve = raw.with_edf(selection.weigh(raw).edf)  # the EDF characterise_channel gives its curve
        low, high = curve.interval()
        truth = np.sqrt(exact_avar(curve.clusters, 0.1, **process))
        held += int(np.sum((low <= truth) & (truth <= high)))
        total += len(truth)
    assert 0.90 <= held / total <= 0.99, held / total


# --------------------------------------------------------------------------- the ramp


@pytest.mark.parametrize(
    "process",
    [dict(arw=1e-3), dict(k=1e-6), dict(sigma_b=1e-3, tau_c=100.0), dict(flicker=1e-3), dict(q=1e-3)],
    ids=["white", "rate_random_walk", "gauss_markov", "flicker", "quantization"],
)
def test_ramp_sigma_is_the_spread_of_noise_slopes(process):
    """The least-squares slope's σ under each noise type (:func:`trend.slope_variance`, the noise's
    spectrum through the slope's window) is the spread of the slopes of 400 generated series within
    15 % (the spread's own standard error is 3.5 %); white noise's is ``√(12 N²/(dt³ n³))`` exactly."""
    n, dt = 1 << 13, 0.1
    slopes = [trend.slope(generate(np.random.default_rng([s, 17]), n, dt, **process), dt, [(0, n)])
              for s in range(400)]  # fmt: skip
    predicted = math.sqrt(trend.slope_variance(n, dt, _coefficients(process), process.get("tau_c")))
    assert float(np.std(slopes)) == pytest.approx(predicted, rel=0.15)
    if "arw" in process:
        assert predicted == pytest.approx(math.sqrt(12.0 * 1e-6 / (dt**3 * (n**3 - n))), rel=1e-4)


# --------------------------------------------------------------------------- issue 32's cases, two seeds


@pytest.fixture(scope="module")
def cases() -> dict[str, list[tuple[analysis.ChannelResult, analysis.ChannelResult]]]:
    """Two seeds of each of issue 32's cases (4 h at 100 Hz): each result and one more refit of it."""
    out = {}
    for case in CASES:
        pairs = []
        for seed in (0, 1):
            x = case_series(case, seed)
            result = analysis.characterise_channel(x, DT)
            pairs.append((result, analysis.refit_channel(x, DT, None, result)))
        out[case] = pairs
    return out


@pytest.mark.parametrize("case", sorted(CASES))
def test_terms_of_issue_32s_cases(cases, case):
    """Two seeds of each case (the 20-seed sweep is ``tools/characterise_recovery.py``): every term of the
    truth resolved (each dominates the curve over an octave and a half or more, the ramp the series) but
    the rate random walk, which a seed in ten leaves bounded; the resolved terms within 3σ of their truth,
    but one statement a case at most (the sweep asks 90 %: on ``accel_n_gm_k``'s seed 1 the Gauss–Markov
    bias takes the rate random walk's rise and lands 3.7σ high, the one miss of its 20 seeds); no term
    absent from the truth beyond 3σ; every unresolved term's bound at or above its truth; and one more
    refit changes no resolved term."""
    truth = truths(case)
    missed = []
    for result, again in cases[case]:
        assert again.fit.resolved == result.fit.resolved, (result.fit.resolved, again.fit.resolved)
        for name, true in truth.items():
            term = result.fit.terms[name]
            if not term.resolved:
                assert term.upper is not None and term.upper >= true, (name, term, true)
                assert true == 0.0 or name == "rate_random_walk", (name, term, true)
                continue
            assert term.value is not None and term.sigma is not None
            if abs(term.value - true) > 3.0 * term.sigma:
                assert true > 0.0, (name, term)
                missed.append((name, term.value, term.sigma, true))
    assert len(missed) <= 1, missed


def test_flicker_and_gauss_markov_told_apart(cases):
    """The flicker case takes B, not a Gauss–Markov bias; the Gauss–Markov cases take GM, not B, and the
    correlation time's range holds the truth in three of their four fits at least."""
    for result, _ in cases["flicker_white"]:
        assert result.fit.terms["flicker"].resolved and not result.fit.terms["gauss_markov"].resolved
    held = 0
    for case in ("gyro_q_n_gm_k", "accel_n_gm_k"):
        for result, _ in cases[case]:
            assert result.fit.terms["gauss_markov"].resolved and not result.fit.terms["flicker"].resolved
            low, high = result.fit.tau_c_range_s or (0.0, 0.0)
            held += low <= CASES[case]["tau_c"] <= high
    assert held >= 3  # a 95 % range; over the sweep's 40 fits, see the guide


def test_ramp_is_a_trend_taken_out_before_the_allan_analysis(cases):
    """The ramp case: the ramp resolved with its sign and σ, taken out of the curve analysed (its Allan
    variance ``R²τ²/2`` gone: the longest cluster time's point within 3σ of white noise's), no rate
    random walk in its place; the other cases: no ramp."""
    for result, _ in cases["white_ramp"]:
        fit = result.fit
        assert fit.ramp_removed and fit.terms["rate_ramp"].resolved and fit.terms["rate_ramp"].value > 0.0
        assert not fit.terms["rate_random_walk"].resolved
        n2 = CASES["white_ramp"]["arw"] ** 2 / result.curve.tau_s[-1]
        assert result.curve.avar[-1] <= n2 * (1.0 + 3.0 * math.sqrt(2.0 / result.curve.edf[-1]))
    for case in ("gyro_q_n_gm_k", "flicker_white", "accel_n_gm_k"):
        for result, _ in cases[case]:
            assert not result.fit.terms["rate_ramp"].resolved and not result.fit.ramp_removed


def test_slow_noise_does_not_pass_for_a_ramp():
    """A Gauss–Markov bias of 300 s over 17 minutes makes trends of its own, which its Allan curve (up
    to 82 s) cannot show: 20 seeds of it give no ramp beyond 3σ (the σ allows for the slow noise the
    curve does not exclude; from the full model alone, the rig recording of issue 32 gave 4σ)."""
    n, dt = int(1046.4 * 100), 0.01
    for seed in range(20):
        x = generate(np.random.default_rng([seed, 41]), n, dt, arw=1e-3, sigma_b=2e-4, tau_c=300.0)
        spans = ((0, n),)
        weights = selection.weigh(allan(x, dt, spans).detrended(trend.slope(x, dt, spans)))
        ramp = trend.fit_ramp(x, dt, spans, weights.slow_models(), weights.tau_c_s)
        assert not ramp.resolved, (seed, ramp)


# --------------------------------------------------------------------------- model file and closing check


def _residual(
    process: dict[str, float], seed: int = 0, n: int = 1 << 15, scale: float = 100.0
) -> analysis.Residual:
    rng = np.random.default_rng(seed)
    x = np.column_stack([generate(rng, n, 0.1, **process) for _ in range(6)])
    x[:, 3:] *= scale  # accelerometers: m/s² scale noise
    return analysis.residual(np.arange(n) * 0.1, x, None, "synthetic")


def test_model_file_is_read_by_sins_and_simulates_the_fitted_noise(tmp_path):
    """The written file loads as an IMU file (no grade, [[effect]] tables); its effects hold the fitted
    terms in SI; simulated, its Allan curves lie within the bands of the real ones."""
    process = dict(arw=1e-3, sigma_b=3e-4, tau_c=20.0)
    result = analysis.characterise(_residual(process))
    path = model_file.write_model(tmp_path / "unit.toml", result)
    spec = scenario.load_imu(path)
    assert spec.grade is None and spec.withhold == ()
    model = spec.model()
    noise = model.get("gyro.noise")
    assert noise is not None
    np.testing.assert_allclose(
        noise.density[0], result.channels["gyro.x"].fit.terms["white"].value, rtol=1e-5
    )
    gm = model.get("gyro.bias_instability")
    assert gm is not None and gm.sigma[0] > 0.0
    closing = check.closing_check(result, model, seed=3)
    assert len(closing.partings) <= 1, [p.what() for p in closing.partings]
    assert not list(tmp_path.glob(".*tmp"))


def test_flicker_is_written_as_the_gauss_markov_bias_of_its_peak(tmp_path):
    """sins has no flicker effect: a resolved B is written as the Gauss–Markov bias of the same Allan peak
    (``0.617 σ_b = 0.664 B``) at the middle of the floor's cluster times, with a comment saying so."""
    process = dict(arw=3e-4, flicker=1e-4)
    result = analysis.characterise(_residual(process, n=1 << 16))
    path = model_file.write_model(tmp_path / "unit.toml", result)
    text = path.read_text()
    assert "simulated as the Gauss-Markov bias of the same Allan peak" in text
    gm = scenario.load_imu(path).model().get("gyro.bias_instability")
    assert gm is not None
    b = result.channels["gyro.x"].fit.terms["flicker"].value
    assert b is not None
    assert gm.sigma[0] * terms.GM_PEAK == pytest.approx(b * terms.FLICKER_FACTOR, rel=1e-5)


def test_model_file_beyond_what_sins_reads_is_refused(tmp_path):
    """A recording whose accelerometer noise would be 1e9 µg/√Hz (readings in other units) is refused in
    one line naming the effect, before anything is written (issue 35)."""
    result = analysis.characterise(_residual(dict(arw=1e-3), n=1 << 12, scale=1e7))
    refusal(lambda: model_file.write_model(tmp_path / "unit.toml", result), "synthetic", "accel.noise",
            "vrw_ug_per_rt_hz")  # fmt: skip
    assert not list(tmp_path.iterdir())


# --------------------------------------------------------------------------- command line


def _write_static(path, n: int = 1 << 14, seed: int = 0, dt: float = 0.1, t0: float = 0.0) -> None:
    rng = np.random.default_rng(seed)
    t = t0 + np.arange(n) * dt
    gyro = np.column_stack([generate(rng, n, dt, arw=1e-4) for _ in range(3)]) + 7e-5
    accel = np.column_stack([generate(rng, n, dt, arw=1e-3) for _ in range(3)]) + np.r_[0.0, 0.0, -9.8]
    io.write_imu(path, ImuRates(t=t, omega_ib_b=gyro, f_ib_b=accel))


def test_cli_round_trip(tmp_path, capsys):
    """`sins characterise REC.csv --static --out --json --rerun`: a table, a loadable IMU file, a JSON in SI
    units with each term's uncertainty and support, and the closing check."""
    rec = tmp_path / "static.csv"
    _write_static(rec)
    out, doc, rrd = tmp_path / "unit.toml", tmp_path / "unit.json", tmp_path / "unit.rrd"
    args = ["characterise", str(rec), "--static", "--out", str(out), "--json", str(doc), "--rerun", str(rrd)]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "°/√h" in text and "closing check" in text and "µg/√Hz" in text and "IEEE B" in text
    data = json.loads(doc.read_text())
    white = data["channels"]["gyro.x"]["terms"]["white"]
    assert white["unit"] == "rad/√s" and white["resolved"]
    assert abs(white["value"] - 1e-4) < 3 * white["sigma"] + 0.02e-4
    assert white["support_tau_s"]
    assert data["channels"]["gyro.x"]["terms"]["rate_ramp"]["simulated"] is False
    assert data["channels"]["gyro.x"]["terms"]["flicker"]["symbol"] == "B"
    assert "closing_check" in data and rrd.stat().st_size > 0
    assert scenario.load_imu(out).model().get("accel.noise") is not None


def test_cli_refusals(tmp_path, capsys):
    """One line and exit 2, and nothing written: no RECORDING and no --dataset, both, an IMU recording
    without --static or --truth, --static beside --truth, an output into a missing folder (refused before
    the work), 16 rows ("infx" once), constant readings ("< -" once); a negative seed is argparse's usage
    error (exit 2), before anything is read or written (issue 35: it failed after writing --out)."""
    rec = tmp_path / "static.csv"
    _write_static(rec, n=256)
    short = tmp_path / "short.csv"
    _write_static(short, n=16)
    flat = tmp_path / "flat.csv"
    t = np.arange(512) * 0.1
    io.write_imu(
        flat, ImuRates(t=t, omega_ib_b=np.full((512, 3), 7e-5), f_ib_b=np.tile([0, 0, -9.8], (512, 1)))
    )
    out = tmp_path / "unit.toml"
    for argv, fragment in (
        (["characterise"], "give a RECORDING or --dataset NAME"),
        (["characterise", str(rec), "--dataset", "ferraris"], "one of them"),
        (["characterise", str(rec), "--out", str(out)], "--static"),
        (["characterise", str(rec), "--static", "--truth", str(rec)], "exclude each other"),
        (["characterise", str(rec), "--static", "--out", str(tmp_path / "no" / "u.toml")], "does not exist"),
        (["characterise", str(short), "--static", "--out", str(out)], "needs at least 128"),
        (["characterise", str(flat), "--static", "--out", str(out)], "gyro.x is constant"),
    ):
        assert cli.main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and fragment in err, err
    with pytest.raises(SystemExit) as info:
        cli.main(["characterise", str(rec), "--static", "--out", str(out), "--seed", "-1"])
    assert info.value.code == 2 and "--seed: must be in [0, 2**63 - 1], got -1" in capsys.readouterr().err
    assert not out.exists()


def test_time_in_milliseconds_is_a_stated_warning(tmp_path, capsys):
    """A 100 Hz recording whose time column is in milliseconds reads as 0.1 Hz: characterised, with a
    one-line warning that says so on stderr and in the JSON."""
    rec = tmp_path / "ms.csv"
    _write_static(rec, n=4096, dt=10.0)
    doc = tmp_path / "ms.json"
    assert cli.main(["characterise", str(rec), "--static", "--json", str(doc)]) == 0
    # On a loaded machine the work may pass 5 s and log progress lines too: the warning is the one line
    # of its own.
    said = [line for line in capsys.readouterr().err.splitlines() if line.startswith("sins:")]
    assert len(said) == 1 and said[0].startswith("sins: warning:") and "milliseconds" in said[0], said
    assert "milliseconds" in json.loads(doc.read_text())["warnings"][0]


def test_static_on_a_moving_recording_is_refused(tmp_path, capsys):
    """`--static` on `sins simulate`'s drive (turns and starts) is refused in one line naming the channel,
    its departure and when, and what to give instead; a static recording with slow drift passes the
    same check."""
    scen, imu_csv, truth = tmp_path / "drive.toml", tmp_path / "imu.csv", tmp_path / "truth.csv"
    scen.write_text(_DRIVE)
    assert (
        cli.main(["simulate", str(scen), "--imu", str(imu_csv), "--truth", str(truth), "--form", "rate"]) == 0
    )
    capsys.readouterr()
    assert cli.main(["characterise", str(imu_csv), "--static"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--static, but the unit moves" in err and "--truth" in err, err
    rng = np.random.default_rng(4)
    n = 36_000
    t = np.arange(n) * 0.1
    readings = np.column_stack([generate(rng, n, 0.1, arw=1e-4, k=1e-6) for _ in range(6)])
    assert still.motion(t, readings + np.r_[7e-5, 0, 0, 0, 0, -9.8]) is None


# --------------------------------------------------------------------------- references


def test_rig_recording_of_a_tactical_unit(tmp_path, capsys):
    """`sins characterise rig.csv` on `sins calibrate 24pos_ratetable --imu tactical`: the seed model
    fitted against the rig's reference and taken away first, the white noise within 10 % of the unit's
    (0.1 °/√h, 100 µg/√Hz) and no rate random walk or ramp resolved (issue 32: N 0, K 768-1264 °/h/√h)."""
    rig = tmp_path / "rig.csv"
    assert cli.main(["calibrate", "24pos_ratetable", "--imu", "tactical", "--out", str(rig)]) == 0
    doc = tmp_path / "rig.json"
    assert cli.main(["characterise", str(rig), "--json", str(doc)]) == 0
    assert "seed model" in capsys.readouterr().out
    data = json.loads(doc.read_text())
    for ch, r in data["channels"].items():
        unit = 0.1 * _DEG / 60 if ch.startswith("gyro") else 100 * 9.80665e-6
        white = r["terms"]["white"]
        assert white["resolved"] and abs(white["value"] / unit - 1.0) <= 0.10, (ch, white)
        assert not r["terms"]["rate_random_walk"]["resolved"] and not r["terms"]["rate_ramp"]["resolved"], ch
    # --static beside a rig recording had been ignored (its ref_ columns taken all the same): refused.
    assert cli.main(["characterise", str(rig), "--static"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--static, but its ref_ columns are its reference" in err, err


def test_rig_session_of_the_written_unit(tmp_path, capsys):
    """The round trip through sins: a unit characterised, its file given to `sins calibrate`, the rig
    recording characterised (its ref_ columns removed): the white noise comes back within 3σ."""
    result = analysis.characterise(_residual(dict(arw=2e-4), n=1 << 14))
    unit = model_file.write_model(tmp_path / "unit.toml", result)
    rig = tmp_path / "rig.csv"
    assert (
        cli.main(["calibrate", "24pos_ratetable", "--imu", str(unit), "--out", str(rig), "--seed", "2"]) == 0
    )
    doc = tmp_path / "rig.json"
    assert cli.main(["characterise", str(rig), "--json", str(doc)]) == 0
    capsys.readouterr()
    channels = json.loads(doc.read_text())["channels"]
    for ch in ("gyro.x", "accel.z"):
        white = channels[ch]["terms"]["white"]
        wrote = result.channels[ch].fit.terms["white"].value
        assert white["resolved"] and abs(white["value"] - wrote) <= 3.0 * white["sigma"], (ch, white, wrote)


_DRIVE = """
name = "short_drive"
description = "two minutes: a hold, a start and a turn"
[imu]
rate_hz = 50
[initial]
lat_deg = 45.0
lon_deg = 7.0
alt_m = 200.0
[[segment]]
type = "hold"
duration_s = 20
[[segment]]
type = "accelerate"
duration_s = 10
to_speed_mps = 10.0
ramp_s = 2.0
[[segment]]
type = "turn"
duration_s = 40
rate_dps = 3.0
ramp_s = 2.0
[[segment]]
type = "hold"
duration_s = 50
"""


def test_moving_unit_with_its_truth(tmp_path, capsys):
    """A moving unit (`sins simulate` of a short drive, numpy white noise added to its rates): with
    `--truth` its motion is removed and the noise read back within 3σ on every channel."""
    scen, imu_csv, truth = tmp_path / "drive.toml", tmp_path / "imu.csv", tmp_path / "truth.csv"
    scen.write_text(_DRIVE)
    assert (
        cli.main(["simulate", str(scen), "--imu", str(imu_csv), "--truth", str(truth), "--form", "rate"]) == 0
    )
    samples = io.read(imu_csv).imu
    assert isinstance(samples, ImuRates)
    rng = np.random.default_rng(9)
    density = np.r_[1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3]  # rad/√s, m/s/√s
    dt = float(np.median(np.diff(samples.t)))
    noise = density / math.sqrt(dt) * rng.standard_normal((len(samples.t), 6))
    noisy = ImuRates(
        t=samples.t, omega_ib_b=samples.omega_ib_b + noise[:, :3], f_ib_b=samples.f_ib_b + noise[:, 3:]
    )
    io.write_imu(imu_csv, noisy)
    doc = tmp_path / "out.json"
    assert cli.main(["characterise", str(imu_csv), "--truth", str(truth), "--json", str(doc)]) == 0
    capsys.readouterr()
    channels = json.loads(doc.read_text())["channels"]
    for i, ch in enumerate(("gyro.x", "gyro.y", "gyro.z", "accel.x", "accel.y", "accel.z")):
        white = channels[ch]["terms"]["white"]
        assert white["resolved"] and abs(white["value"] - density[i]) <= 3.0 * white["sigma"], (ch, white)


# --------------------------------------------------------------------------- real recordings


def _real(name: str, folder: str) -> tuple[analysis.Characterisation, check.ClosingCheck, check.ClosingCheck]:

    if not dataset_folder(folder).is_dir():
        pytest.skip(f"dataset {folder} not found under the data root")
    data = io.read(dataset=name).reference_inputs()[0]
    result = analysis.characterise(reference.reference_residual(data, name))
    model = model_file.imu_model(result)
    return result, check.closing_check(result, model, seed=1), check.closing_check(result, model, seed=2)


def _within_model(
    closing: check.ClosingCheck, result: analysis.Characterisation, fast_gm: bool = True
) -> float:
    """The share of points where the simulated curve lies within the band about the fitted model's.

    ``fast_gm=False`` leaves out the cluster times of at most four samples on channels whose Gauss–Markov
    bias has a correlation time under 20 samples: there the simulated bias (sampled, and integrated by the
    trapezoid rule) has less Allan variance than the continuous form the fit uses, by ``O(dt/T)``.
    """
    from scipy import stats

    inside = total = 0
    for ch, c in closing.channels.items():
        edf = result.channels[ch].curve.edf
        ratio = np.asarray(c["sim_adev"]) ** 2 / np.asarray(c["model_adev"]) ** 2
        lo, hi = stats.chi2.ppf(0.005, edf) / edf, stats.chi2.ppf(0.995, edf) / edf
        keep = np.ones(len(ratio), dtype=bool)
        tau_c = result.channels[ch].fit.tau_c_s
        if not fast_gm and tau_c is not None and tau_c < 20.0 * result.dt:
            keep = np.asarray(c["tau_s"]) > 4.5 * result.dt
        inside += int(np.sum(((ratio >= lo) & (ratio <= hi))[keep]))
        total += int(keep.sum())
    return inside / total


def test_ferraris_round_trip(capsys):
    """The Ferraris holds (six of 4-7 s at 102.4 Hz): white noise resolved on every channel, the slow terms
    not resolved with the length they need; the model file's simulation follows the fitted model at 95 %
    of points; the real curves part from the simulated ones only at the shortest cluster times (the
    unit's output filter), with two seeds."""
    result, one, two = _real("ferraris", "imucal_ferraris")
    assert cli.main(["characterise", "--dataset", "ferraris"]) == 0
    capsys.readouterr()
    for r in result.channels.values():
        assert r.fit.terms["white"].resolved
        for name in ("flicker", "gauss_markov", "rate_random_walk"):
            assert not r.fit.terms[name].resolved and r.fit.terms[name].needs_length_s
    assert _within_model(one, result) >= 0.95
    for closing in (one, two):
        for p in closing.partings:
            assert p.tau_s[1] <= 2.5 * result.dt or abs(math.log(p.ratio)) < 0.25, p.what()


def _broad_rest(name: str, trial: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """BROAD's own rest phases (its ``movement`` flags, read here with scipy): rows of the reader's trial
    (True at rest), the gyro readings and the sample step."""

    mat = scipy.io.loadmat(str(dataset_folder("broad_mocap") / f"{trial}.mat"), squeeze_me=True)
    data = io.read(dataset=name).reference_inputs()[0]
    dt = 7.0 / 2000.0
    rest = ~np.asarray(mat["movement"]).astype(bool)[np.round(data.t / dt).astype(int)]
    return rest, data.gyro, np.array(dt)


@pytest.mark.parametrize(
    "name, trial",
    [
        ("broad_05", "05_undisturbed_slow_rotation_with_breaks_B"),
        ("broad_18", "18_undisturbed_fast_translation_with_breaks_B"),
    ],
)
def test_broad_reference_noisier_than_the_sensor(name, trial):
    """BROAD's reference is differentiated motion capture: the report says it limits the moving parts,
    the sensor is characterised where it stood still (every still row is a rest by BROAD's own flags, and
    they cover 85 % of its rests or more), and the gyro white noise is within 20 % of the rest phases' own
    Allan figure (allantools' ``oadev`` of the readings over BROAD's rests, each trimmed by a second:
    ``σ(τ)·√τ`` at the octave of least slope error, 0.1-0.5 s)."""
    if not dataset_folder("broad_mocap").is_dir():
        pytest.skip("dataset broad_mocap not found under the data root")

    data = io.read(dataset=name).reference_inputs()[0]
    res = reference.reference_residual(data, name)
    assert any("limited by the reference" in note for note in res.notes), res.notes
    rest, gyro, dt = _broad_rest(name, trial)
    kept = np.zeros(len(data), dtype=bool)
    for a, b in res.segments:
        kept[a:b] = True
    assert kept[~rest].sum() == 0 and kept[rest].mean() >= 0.85
    result = analysis.characterise(res, ("gyro.x", "gyro.y", "gyro.z"))
    edges = np.diff(np.r_[0, rest.astype(np.int8), 0])
    trim = int(1.0 / dt)
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    spans = [(a + trim, b - trim) for a, b in zip(starts, stops, strict=True) if b - a > 4 * trim]
    for i, ch in enumerate(("gyro.x", "gyro.y", "gyro.z")):
        n_own = _white_figure([gyro[a:b, i] for a, b in spans], float(dt))
        white = result.channels[ch].fit.terms["white"]
        assert white.resolved and white.value is not None
        assert abs(white.value / n_own - 1.0) <= 0.20, (ch, white.value, n_own)


def _white_figure(pieces: list[np.ndarray], dt: float) -> float:
    """White rate noise from allantools' overlapping deviation of each rest piece, pooled by counts: the
    median of ``σ(τ)√τ`` at τ = 0.1-0.5 s (white noise's −½ slope holds there on BROAD's gyro)."""
    taus = np.array([0.1, 0.2, 0.4])
    values = []
    for piece in pieces:
        t, adev, _, _ = allantools.oadev(piece, rate=1.0 / dt, data_type="freq", taus=taus)
        values.append(adev * np.sqrt(t))
    return float(np.median(np.concatenate(values)))


def _rocking_hz(name: str) -> tuple[float, float]:
    """The frequency (1-4 Hz) where the ring-laser unit's x gyro and y accelerometer are most coherent, and
    that coherence: the base rocking about the x axis turns the gyro and tilts gravity into the y axis."""
    from scipy import signal

    data = io.read(dataset=name).reference_inputs()[0]
    fs = 1.0 / float(np.median(np.diff(data.t)))
    f, c = signal.coherence(data.gyro[:, 0], data.accel[:, 1], fs=fs, nperseg=4096)
    band = (f > 1.0) & (f < 4.0)
    k = int(np.argmax(c[band]))
    return float(f[band][k]), float(c[band][k])


def test_psins_lasergyro_round_trip():
    """The static ring-laser INS (31 min at 100 Hz): its quantization is coarse against its noise, so the
    file simulates the IEEE Q term as white noise of the integrated output (``quantization_noise``), not as
    rounding; the simulation follows the fitted model at 95 % of points or more; and at the points the
    fit kept the curves part only where the real unit's curve is not its noise:

    * the vertical channels (gyro.z, accel.z): at most one parting a seed (about 30 points at 99 %);
    * the horizontal ones, about which the base rocks near 2 Hz (the x gyro and the y accelerometer
      coherent above 0.9 there): from a fifth of the line's Allan hump (``0.371/f``) on, where its lobes
      run on beyond the hump and no IEEE term has them, by a factor 1.5 at most; or at the two longest
      cluster times, where the base's slow tilt moves gravity into the horizontal accelerometers (the x
      accelerometer's curve rises there with a slope of about +1/3, between flicker and a rate random
      walk; the fit takes a rate random walk, which the real unit lies below by a factor 3 at 82-164 s).
    """
    result, one, two = _real("psins_lasergyro", "psins_lasergyro_static")
    names = {name for name, _ in model_file.effect_tables(result)}
    assert {"gyro.quantization_noise", "accel.quantization_noise"} <= names
    assert not names & {"gyro.quantization", "accel.quantization"}
    for ch, r in result.channels.items():
        if r.fit.terms["quantization"].resolved:
            assert not model_file.rounding_is_dithered(result, ch)
    f_hz, coherence = _rocking_hz("psins_lasergyro")
    assert coherence > 0.9
    hump_s = 0.371 / f_hz
    for closing in (one, two):
        assert _within_model(closing, result, fast_gm=False) >= 0.95
        kept = [p for p in closing.partings if p.fitted]
        vertical = [p for p in kept if p.channel in ("gyro.z", "accel.z")]
        assert sum(_points(closing, p) for p in vertical) <= 1, [p.what() for p in kept]
        for p in kept:
            if p in vertical:
                continue
            slow = p.tau_s[0] >= closing.channels[p.channel]["tau_s"][-2]
            assert slow or (p.tau_s[0] >= hump_s / 5.0 and 1.0 / 1.5 <= p.ratio <= 1.5), p.what()


def _points(closing: check.ClosingCheck, parting: check.Parting) -> int:
    tau = np.asarray(closing.channels[parting.channel]["tau_s"])
    return int(np.count_nonzero((tau >= parting.tau_s[0]) & (tau <= parting.tau_s[1])))


def test_residual_refusals():
    """Uneven sampling, time that does not increase and too few rows are refused in one line naming the
    source and the row."""
    t = np.arange(300) * 0.1
    x = np.random.default_rng(0).standard_normal((300, 6))
    refusal(lambda: analysis.residual(t[:16], x[:16], None, "rec.csv"), "rec.csv", "16 rows", "at least 128")
    uneven = t.copy()
    uneven[150:] += 0.03  # one step of 0.13 s: not a gap (0.15 s), not the sampling step either
    refusal(lambda: analysis.residual(uneven, x, None, "rec.csv"), "rec.csv", "row 151", "uniform sampling")
    back = t.copy()
    back[30] = back[29]
    refusal(lambda: analysis.residual(back, x, None, "rec.csv"), "rec.csv", "does not increase")
    with pytest.raises(SinsInputError):
        analysis.residual(t, np.full((300, 6), np.nan), None, "rec.csv")


def test_a_parting_without_a_ratio_is_written_as_json_can_say():
    """A model with no noise where the real unit has some parts at an infinite ratio: the JSON says null
    (JSON has no infinity; the fuzzing of issue 35 found `Infinity` written) and the words say why."""
    parting = check.Parting("gyro.x", (0.01, 0.04), math.inf)
    doc = check.ClosingCheck(seed=0, confidence=0.99, partings=(parting,)).to_dict()
    text = json.dumps(doc, allow_nan=False)
    assert json.loads(text)["partings"][0]["ratio"] is None
    assert "no noise" in doc["partings"][0]["what"]


def test_a_term_the_data_give_no_bound_is_said_so(tmp_path, capsys):
    """EuRoC MH_01's rests (15 s beside the motors' vibration) leave a Gauss–Markov bias that no fit holds
    beside the resolved terms on some channels: the table printed ``not resolved (< -)`` and the model
    file said nothing of it, where it bounds every other unresolved term. Both say it has no bound now."""
    if not dataset_folder("euroc").is_dir():
        pytest.skip("dataset euroc not found under the data root")
    out = tmp_path / "m.toml"
    assert cli.main(["characterise", "--dataset", "euroc/MH_01_easy", "--out", str(out)]) == 0
    table = capsys.readouterr().out
    assert "(< -)" not in table
    # what a slow term needs is a longer stretch, not a longer recording (this one is 182 s; its rests 15 s)
    assert "needs a stretch of ≥ 42 s" in table and "of recording" not in table
    unbounded = [line.split()[0] for line in table.splitlines() if line.endswith(analysis.UNBOUNDED)]
    assert unbounded, table
    written = out.read_text()
    for ch in unbounded:
        assert f"# {ch}: gauss_markov not resolved, {analysis.UNBOUNDED}" in written


def test_a_resolved_term_that_leads_at_no_cluster_time_says_how_it_is_resolved(capsys):
    """PSINS's laser-gyro INS resolves accel.y's white noise by the joint fit, where it holds half the
    Allan variance at no cluster time: its support column was empty, as if nothing stood behind it."""
    if not dataset_folder("psins_lasergyro_static").is_dir():
        pytest.skip("dataset psins_lasergyro_static not found under the data root")
    assert cli.main(["characterise", "--dataset", "psins_lasergyro"]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()]
    white = next(r for r in rows if r[:2] == ["accel.y", "N"])
    assert " ".join(white).endswith("under half the variance at every τ; resolved by the joint fit"), white
