"""attitude.app.plot: every figure renders to a non-trivial PNG; ``attitude run --plot``."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att

mpl = pytest.importorskip("matplotlib")
from matplotlib.image import imread  # noqa: E402

from attitude.app import plot  # noqa: E402
from attitude.model.torques import from_config  # noqa: E402
from tests.app.test_cli import attitude  # noqa: E402
from tests.app.test_scenario import GOOD, write  # noqa: E402


def _eph(torques=None):
    body = att.RigidBody.from_principal_moments([0.61, 0.965, 1.0])
    state = att.AttitudeState(epoch=att_time(), attitude=Rotation.from_euler("ZXZ", [1, 2, 3]),
                              omega_body=[0.02, 0.0, 0.1])
    return att.propagate(body, state, np.linspace(0, 600, 601), torques=torques)


def att_time():
    from astropy.time import Time

    return Time("2029-04-13T00:00:00", scale="tdb")


def _non_trivial(path):
    img = imread(path)
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200
    rgb = (img[..., :3] * 255).astype(np.uint8).reshape(-1, 3)
    colours = np.unique(rgb, axis=0)
    non_white = np.mean(np.any(rgb < 250, axis=1))
    assert len(colours) > 20, path
    assert 0.01 < non_white < 0.9, (path, non_white)


@pytest.mark.parametrize("name", ["polhode", "herpolhode", "body_axes", "euler_angles",
                                  "regime"])
def test_every_figure_renders_non_trivially(tmp_path, name):
    eph = _eph()
    fig = plot.FIGURES[name](eph)
    assert isinstance(fig, mpl.figure.Figure)
    path = tmp_path / f"{name}.png"
    fig.savefig(path, dpi=80)
    _non_trivial(path)


@pytest.mark.slow      # a long study (> 9 s); the slow tier, which CI runs
def test_regime_timeline_of_a_perturbed_run(tmp_path):
    eph = _eph([from_config({"type": "dissipation", "time_constant": "5 min"})])
    paths = plot.save_figures(eph, tmp_path / "diss", att.classify(eph, require_periods=False))
    assert [p.name for p in paths] == [f"diss_{n}.png" for n in plot.FIGURES]
    for p in paths:
        _non_trivial(p)


def test_run_plot_writes_pngs_next_to_the_output(tmp_path):
    path = write(tmp_path, GOOD)
    proc = attitude("run", path, "--plot", "--quiet")
    assert proc.returncode == 0, proc.stderr
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == sorted(f"out_{n}.png" for n in plot.FIGURES if n != "regime")


def test_run_plot_without_matplotlib_exits_2(tmp_path):
    import subprocess
    import sys

    path = write(tmp_path, GOOD)
    code = ("import sys; sys.modules['matplotlib'] = None; from attitude.app.cli import main; "
            f"sys.exit(main(['run', {str(path)!r}, '--plot']))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "matplotlib" in proc.stderr and str(path) in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_ensemble_spread_figure(tmp_path):
    import astropy.units as u

    ens = att.Ensemble.sample(
        80, rng=4, epoch=att_time(), mean={
            "angular_momentum_ra": 250 * u.deg, "angular_momentum_dec": -75 * u.deg,
            "energy_ratio": 1.024, "ratio_a": 0.61, "ratio_b": 0.965,
            "precession_period": 27.38 * u.h},
        sigma={"precession_period": 0.05 * u.h, "energy_ratio": 0.003})
    eph = att.propagate(ens, np.linspace(0, 20 * 86400.0, 81))
    paths = plot.save_figures(eph, tmp_path / "cloud")
    assert [p.name for p in paths] == [f"cloud_{n}.png" for n in plot.ENSEMBLE_FIGURES]
    for p in paths:
        _non_trivial(p)
    # a catalogue (no nominal member) gets the population figure only
    cat = att.propagate(ens.subset(slice(1, None)), np.linspace(0, 86400.0, 11))
    assert "nominal_body" not in cat.dataset.attrs
    assert list(plot.figures(cat)) == ["regimes"]
