"""The figures of an inversion hold the data, the model, the scan, the chi2 map and the
shape they say they show (their data, not their pixels)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from attitude.inversion.invert import (  # noqa: E402
    _example_observations,
    _example_result,
    invert,
    period_scan,
)
from attitude.inversion.observations import engine_blocks  # noqa: E402
from attitude.inversion.plot import (  # noqa: E402
    lightcurve_figure,
    periodogram_figure,
    pole_map,
    pole_map_figure,
    save_inversion_figures,
    shape_figure,
)


def test_the_lightcurve_figure_draws_each_lightcurve_and_its_model():
    obs, res = _example_observations(), _example_result()
    fig = lightcurve_figure(obs, res)
    start = 0
    for ax, block in zip(fig.axes, engine_blocks(obs)):
        data, model = ax.lines
        n = len(block)
        np.testing.assert_array_equal(data.get_ydata(),
                                      block.brightness / block.brightness.mean())
        np.testing.assert_array_equal(model.get_ydata(), res.fit.model[start:start + n])
        np.testing.assert_array_equal(data.get_xdata(), (block.time - block.time[0]) / 3600)
        start += n
    assert start == res.fit.model.size


def test_the_periodogram_draws_the_scan():
    obs = _example_observations()
    scan = period_scan(obs, [7100.0, 7200.0, 7300.0], poles=2, rows=3, degree=2,
                       max_iterations=5)
    line = periodogram_figure(scan).axes[0].lines[0]
    np.testing.assert_array_equal(line.get_xdata(), scan.periods / 3600.0)
    np.testing.assert_array_equal(line.get_ydata(), scan.chi2)
    assert _example_result().scan is None              # a period given: no scan


@pytest.mark.slow
def test_an_inversion_over_a_period_range_keeps_its_scan():
    obs = _example_observations()
    res = invert(obs, period=(7190.0, 7210.0), poles=10, rows=4, degree=2)
    assert res.scan is not None and res.scan.periods.size >= 3
    assert res.scan.best == pytest.approx(7200.0, rel=1e-6)


def test_the_pole_map_is_lowest_next_to_the_solution():
    obs, res = _example_observations(), _example_result()
    m = pole_map(obs, res, n_longitude=12, n_latitude=7, max_iterations=10)
    # the grid is 30 deg apart: its lowest point is within a cell of the pole or mirror
    lon, lat = m.best
    pole = np.radians(res.pole)
    cells = []
    for l0 in (pole[0], pole[0] + np.pi):
        u = [np.cos(pole[1]) * np.cos(l0), np.cos(pole[1]) * np.sin(l0), np.sin(pole[1])]
        v = [np.cos(np.radians(lat)) * np.cos(np.radians(lon)),
             np.cos(np.radians(lat)) * np.sin(np.radians(lon)), np.sin(np.radians(lat))]
        cells.append(np.degrees(np.arccos(np.clip(np.dot(u, v), -1, 1))))
    assert min(cells) <= 30.0
    assert m.chi2.min() >= res.chi2 * (1 - 1e-9) - 1e-12   # the solution is the minimum
    image = pole_map_figure(m, res).axes[0].collections[0].get_array()
    np.testing.assert_allclose(np.asarray(image).reshape(m.chi2.shape),
                               np.log10(np.maximum(m.chi2, np.finfo(float).tiny)))


def test_the_shape_figure_draws_every_facet(tmp_path):
    res = _example_result()
    fig = shape_figure(res)
    assert [len(ax.collections[0].get_facecolor()) for ax in fig.axes] == \
        [len(res.shape.faces)] * 3
    obs = _example_observations()
    small = pole_map(obs, res, n_longitude=4, n_latitude=3, max_iterations=2)
    paths = save_inversion_figures(obs, res, tmp_path / "demo", pole=small)
    assert [p.name for p in paths] == ["demo_fit.png", "demo_pole_map.png",
                                       "demo_shape_view.png"]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_tumblers_map_is_over_the_direction_of_l():
    from attitude.inversion.invert import _example_tumbler

    obs, truth = _example_tumbler()
    res = invert(obs, rotation="tumbling", start=truth, rows=4, degree=2,
                 alternatives=False)
    m = pole_map(obs, res, n_longitude=6, n_latitude=3, max_iterations=3)
    assert m.kind == "L" and m.chi2.shape == (3, 6)
    # noise-free data fitted to 1e-30: every direction but the solution's fits worse
    assert np.isfinite(m.chi2).all() and m.chi2.min() > 1e3 * res.chi2
    assert "angular momentum L" in pole_map_figure(m, res).axes[0].get_title()
