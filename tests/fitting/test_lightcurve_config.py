"""Lightcurves in the scenario's [observations] table and `attitude fit` on them.

scenarios/nea_lightcurve_fit.toml holds three nights of synthetic photometry of a
tumbling asteroid (scenarios/data/nea_lightcurve.csv).  The data file is regenerated here
from the truth its comment states (the same reader, geometry and forward model) and
compared with the committed file, so that the truth the fit is checked against is the one
the data were made from.  Independent references: the truth itself (within 3 sigma of
the fit's uncertainties) and the injected nightly zero points.
"""

import time
from pathlib import Path

import numpy as np
import pytest
from astropy.time import Time
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.app.scenario import load_scenario
from attitude.fitting import PARAMETERS, free_parameters
from attitude.fitting.observations import seconds_since
from attitude.foundations.errors import ScenarioError
from attitude.photometry.geometry import AU, SPEED_OF_LIGHT

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "nea_lightcurve_fit.toml"
DATA = ROOT / "scenarios" / "data" / "nea_lightcurve.csv"

# the truth (scenarios/nea_lightcurve_fit.toml, comment)
TRUE_BODY = att.RigidBody.from_principal_moments([0.62e12, 0.88e12, 1.0e12])
_W0 = 2 * np.pi / (5.0 * 3600.0)
TRUE_STATE = att.AttitudeState("2026-03-10T00:00:00", Rotation.from_euler(
    "ZXZ", [40.0, 55.0, 20.0], degrees=True), np.array([0.45, 0.35, 1.0]) * _W0,
    frame="ECLIPJ2000")
SIGMA = 0.015
ZERO_POINTS = np.array([15.82, 16.37, 15.64])          # mag, one per night
NIGHTS = (("2026-03-10T01:00:00", 4.0), ("2026-03-11T00:30:00", 4.5),
          ("2026-03-13T01:30:00", 3.5))                # UTC start, hours


def _times_and_sessions(rng):
    jd, session = [], []
    for k, (start, hours) in enumerate(NIGHTS):
        t0 = Time(start, scale="utc").jd
        n = int(round(hours * 15)) + 1                 # 4 min cadence
        keep = rng.uniform(size=n) > 0.05              # a few points lost to clouds
        jd.extend((t0 + np.arange(n)[keep] * 4.0 / 1440.0).tolist())
        session.extend([k + 1] * int(keep.sum()))
    return np.array(jd), np.array(session)


def _write(path, jd, mag, session):
    lines = ["# SYNTHETIC: see scenarios/nea_lightcurve_fit.toml", "jd,mag,session"]
    lines += [f"{j:.8f},{m:.4f},{s}" for j, m, s in zip(jd, mag, session)]
    path.write_text("\n".join(lines) + "\n")


def synthesise(folder: Path) -> Path:
    """The data file, from the truth: the scenario's own reader gives the geometry and the
    light times (a first file with zero magnitudes), the exact solution the attitudes at
    the emission times, the forward model the magnitudes."""
    rng = np.random.default_rng(2026)
    jd, session = _times_and_sessions(rng)
    (folder / "data").mkdir(exist_ok=True)
    target = folder / "data" / "nea_lightcurve.csv"
    _write(target, jd, np.zeros(jd.size), session)
    toml = folder / "nea.toml"
    toml.write_text(SCENARIO.read_text())
    obs = load_scenario(toml).observations.observations[0]
    t = seconds_since(TRUE_STATE.epoch, obs.times) - obs.delay
    q = att.propagate(TRUE_BODY, TRUE_STATE, t).dataset["quaternion"].values
    mag = obs.model_magnitudes(q[None])[0] + ZERO_POINTS[session - 1] \
        + SIGMA * rng.standard_normal(jd.size)
    _write(target, jd, mag, session)
    return target


def test_the_data_file_is_made_from_the_stated_truth(tmp_path):
    made = synthesise(tmp_path).read_text().splitlines()
    committed = DATA.read_text().splitlines()
    assert len(made) == len(committed)
    for a, b in zip(made[2:], committed[2:]):
        ja, ma, sa = a.split(",")
        jb, mb, sb = b.split(",")
        assert ja == jb and sa == sb
        # written with 4 decimals: the two paths agree far below the last digit, so
        # at most one unit of it apart where a value sits on a rounding boundary
        assert abs(float(ma) - float(mb)) <= 1.0001e-4


def test_the_lightcurve_table_reads_into_observations():
    sc = load_scenario(SCENARIO)
    (obs,) = sc.observations.observations
    assert isinstance(obs, att.LightcurveObservations)
    assert obs.n_residuals == 176 and obs.n_nuisance == 3
    np.testing.assert_array_equal(obs.sigma, np.full(176, SIGMA))
    # the geometry from the orbit: 0.43 AU from the Earth, 68-69.4 deg phase, and the
    # light time the distance over c
    assert 0.42 < obs.geometry.observer_distance.min() / AU < 0.44
    phase = np.degrees(obs.geometry.phase_angle)
    assert 67.5 < phase.min() < phase.max() < 69.5
    np.testing.assert_allclose(obs.delay, obs.geometry.observer_distance
                               / SPEED_OF_LIGHT, rtol=1e-12)
    assert len(obs.shape.faces) == 320


def _wrap(d, name):
    """Angle differences into (-pi, pi]; psi0 modulo pi: the ellipsoid is symmetric
    under the half-turn about its C axis, which the light cannot tell apart."""
    period = np.pi if name == "psi0" else 2 * np.pi
    if name in ("angular_momentum_ra", "phi0", "psi0"):
        d = (d + period / 2) % period - period / 2
    return d


def test_attitude_fit_recovers_the_state_and_the_zero_points(tmp_path, capsys):
    from attitude.app.cli import main
    out = tmp_path / "fitted.toml"
    start = time.process_time()
    assert main(["fit", str(SCENARIO), "-o", str(out)]) == 0
    cpu = time.process_time() - start
    text = capsys.readouterr().out
    assert "converged" in text and "regime SAM" in text
    assert "chi2" in text and "for 165 degrees of freedom" in text     # 176 - 8 - 3
    assert cpu < 10.0, cpu              # about 1 s of CPU: from the guess only
    assert "# Fitted by" in out.read_text() and "lightcurve 0 session 2: offset" \
        in out.read_text()                          # the offsets, in the header comment
    fitted = load_scenario(out)
    p_fit, _ = free_parameters(fitted.body, fitted.state)
    p_true, _ = free_parameters(TRUE_BODY, TRUE_STATE)
    # the printed 1-sigma (degrees for the angles)
    rows = {line.split()[0]: line.split() for line in text.splitlines()
            if line.strip().split(" ")[0] in PARAMETERS}
    for name in PARAMETERS:
        sigma = float(rows[name][3]) * (np.pi / 180 if rows[name][4:5] == ["deg"] else 1)
        d = _wrap(p_fit[name] - p_true[name], name)
        assert abs(d) < 3 * sigma, (name, d, sigma)
    # the nightly zero points come back up to one common constant (the model magnitude
    # of the ellipsoid is in arbitrary units): their differences, within 3 sigma
    offsets = [line.split() for line in text.splitlines()
               if line.strip().startswith("session ")]
    assert [o[1] for o in offsets] == ["1", "2", "3"]     # the file's session numbers
    b = np.array([float(o[2]) for o in offsets])
    s = np.array([float(o[4]) for o in offsets])
    diff = np.diff(b) - np.diff(ZERO_POINTS)
    assert np.all(np.abs(diff) < 3 * np.hypot(s[1:], s[:-1])), (diff, s)


def _variant(tmp_path, old, new):
    text = SCENARIO.read_text()
    assert old in text
    (tmp_path / "data").mkdir(exist_ok=True)
    (tmp_path / "data" / "nea_lightcurve.csv").write_text(DATA.read_text())
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize("old, new, key", [
    ('sigma = "0.015 mag"', "", "observations.lightcurve[0].sigma"),
    ('law = "ls-lambert"', 'law = "no-such-law"', "observations.lightcurve[0].law"),
    ('file = "data/nea_lightcurve.csv"', 'file = "data/missing.csv"',
     "observations.lightcurve[0].file"),
    ('orbit = {', 'sun = [1.0, 0.0, 0.0]\norbit = {', "observations.lightcurve[0]"),
    ('axes = { value = [600, 460, 378]', 'axes = { value = [600, 460]',
     "observations.lightcurve[0].axes"),
    ('e = 0.22', 'e = 1.5', "observations.lightcurve[0].orbit.e"),
    ('sessions = true', 'session = true', "observations.lightcurve[0].session"),
])
def test_bad_lightcurve_tables_name_the_key(tmp_path, capsys, old, new, key):
    path = _variant(tmp_path, old, new)
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert err.value.key.startswith(key), (err.value.key, str(err.value))
    from attitude.app.cli import main
    assert main(["fit", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and key in lines[0], lines


def test_an_alcdef_file_gives_sessions_errors_and_asteroid_times(tmp_path):
    """The first two nights as ALCDEF blocks (MAGERR given, LTCAPP=NONE with each
    night's mean light time): two sessions, the file's uncertainties, and times moved to
    the asteroid by the reader, so no second light-time delay; they match the CSV's
    emission times to within the change of the light time over a night (the distance
    changes by < 20 km/s x 4.5 h: < 1.1 s)."""
    csv_obs = load_scenario(SCENARIO).observations.observations[0]
    epoch = TRUE_STATE.epoch
    rows = [line.split(",") for line in DATA.read_text().splitlines()[2:]]
    jd = np.array([float(r[0]) for r in rows])
    mag = np.array([float(r[1]) for r in rows])
    night = np.array([int(r[2]) for r in rows])
    blocks = []
    for k in (1, 2):
        sel = night == k
        ltc = csv_obs.delay[sel].mean() / 86400.0
        blocks += ["STARTMETADATA", "OBJECTNAME=Synthetic NEA", "DELIMITER=PIPE",
                   "LTCAPP=NONE", f"LTCDAYS={ltc:.9f}", "ENDMETADATA"]
        blocks += [f"DATA={j:.8f}|{m:.4f}|0.015" for j, m in zip(jd[sel], mag[sel])]
        blocks += ["ENDDATA"]
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "nea.alcdef").write_text("\n".join(blocks) + "\n")
    text = SCENARIO.read_text().replace('file = "data/nea_lightcurve.csv"',
                                        'file = "data/nea.alcdef"')
    text = text.replace('sigma = "0.015 mag"', "")
    (tmp_path / "alcdef.toml").write_text(text)
    (obs,) = load_scenario(tmp_path / "alcdef.toml").observations.observations
    n = int((night <= 2).sum())
    assert obs.n_residuals == n and obs.n_nuisance == 2
    np.testing.assert_array_equal(obs.sigma, np.full(n, 0.015))
    np.testing.assert_array_equal(obs.delay, np.zeros(n))
    emitted_csv = seconds_since(epoch, csv_obs.times)[night <= 2] - csv_obs.delay[night <= 2]
    assert np.abs(seconds_since(epoch, obs.times) - emitted_csv).max() < 1.1
