"""The spin-orbit wing (issue 19): resonances, forced libration, 3-D stability, surfaces of
section, despinning, the [section] table and ``attitude section``.

Independent references: the tabulated Cayley series (Murray & Dermott 1999, Table 5.1) and
Parseval's identity for the numerical transform; the gravity-gradient torque of
``attitude.model.torques`` for the planar equation; the linear forced-libration theory for the
3-D propagation; Floquet theory (area preservation, reciprocal pairs); the published
libration anchors (shared/validation/README.md); the chaos verdict of ``lyapunov.py`` on
the 3-D problem for the planar batch verdict.
"""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import attitude as att
from attitude.analysis.lyapunov import lyapunov_exponent
from attitude.app.cli import main
from attitude.app.scenario import load_scenario
from attitude.foundations.errors import ScenarioError, SpinOrbitError
from attitude.foundations.expectation import Expectation
from attitude.model.torques import GravityGradient
from attitude.spinorbit import (
    cayley_coefficient,
    cayley_series,
    despinning_time,
    forced_libration_amplitude,
    love_number_k2,
    measure_libration,
    overlap_parameter,
    periodic_orbit,
    planar_rhs,
    resonance_list,
    stroboscopic_map,
)
from attitude.spinorbit.section import (
    expectation_values,
    load_tables,
    mean_spin_resonance,
    parse_expect,
    parse_section,
)

ROOT = Path(__file__).resolve().parents[2]
MARS_MU = 4.282837e13


def hyperion(**kw) -> att.SpinOrbit:
    orbit = att.KeplerOrbit.from_elements(mu="3.7931e16 m3/s2", a="1.4811e9 m", e=0.1, **kw)
    return att.SpinOrbit.from_omega0(0.89, orbit)


# --- resonances ------------------------------------------------------------------------

# 2p -> power of the first neglected term of the two-term series (Table 5.1)
NEXT_POWER = {-1: 5, 1: 5, 2: 6, 3: 5, 4: 6, 5: 7, 6: 8}


@pytest.mark.parametrize("two_p", sorted(NEXT_POWER))
def test_cayley_transform_matches_the_tabulated_series_to_the_next_order(two_p):
    """The numerical Fourier transform and the series differ by the first neglected term:
    the difference scales as e^k with k the next power (halving e divides it by ~2^k)."""
    p = Fraction(two_p, 2)
    d = [abs(cayley_coefficient(p, e) - cayley_series(p, e)) for e in (0.02, 0.01)]
    order = math.log2(d[0] / d[1])
    assert abs(order - NEXT_POWER[two_p]) < 0.15, order


def test_cayley_coefficients_satisfy_parseval():
    """sum_p H(p, e)^2 = <(a/r)^6>_M = (1 + 3 e^2 + 3 e^4 / 8) / (1 - e^2)^(9/2)."""
    for e in (0.1, 0.4):
        total = sum(cayley_coefficient(Fraction(k, 2), e) ** 2 for k in range(-40, 81))
        exact = (1 + 3 * e**2 + 3 * e**4 / 8) / (1 - e**2) ** 4.5
        assert total == pytest.approx(exact, rel=1e-12)


def test_circular_orbit_has_only_the_synchronous_term():
    assert cayley_coefficient(1, 0.0) == pytest.approx(1.0, abs=1e-15)
    for p in (0.5, 1.5, 2, 3):
        assert abs(cayley_coefficient(p, 0.0)) < 1e-15


def test_resonance_widths_and_the_hyperion_overlap():
    res = {r.name: r for r in resonance_list(0.89, 0.1)}
    assert list(res)[:4] == ["1:2", "1:1", "3:2", "2:1"]
    for r in res.values():
        assert r.half_width == pytest.approx(0.89 * math.sqrt(abs(r.H)), rel=1e-15)
        assert r.centre == (0.0 if r.H > 0 else math.pi / 2)
    assert res["1:2"].H < 0 and res["1:1"].H > 0
    # WPM 1984: the 1:1 and 3:2 resonances overlap when omega0 > 1 / (2 + sqrt(14 e))
    # (H(1) ~ 1, H(3/2) ~ 7e/2 for small e); Hyperion is far beyond
    assert overlap_parameter(res["1:1"], res["3:2"]) > 2
    e = 0.001
    w_star = 1.0 / (2.0 + math.sqrt(14 * e))
    for w, above in ((0.99 * w_star, False), (1.01 * w_star, True)):
        one, three_halves = resonance_list(w, e)[1:3]
        assert (overlap_parameter(one, three_halves) > 1) is above


def test_bad_resonance_inputs_raise_spin_orbit_error():
    with pytest.raises(SpinOrbitError, match="half-integer"):
        cayley_coefficient(2.25, 0.1)
    with pytest.raises(SpinOrbitError, match=r"e: must be in \[0, 1\)"):
        cayley_coefficient(1, 1.2)
    with pytest.raises(SpinOrbitError, match="KeplerOrbit"):
        att.SpinOrbit(att.RigidBody.from_principal_moments([1, 2, 2.5]), object())


# --- the planar problem and the 3-D torque ----------------------------------------------

def test_planar_equation_is_the_gravity_gradient_torque_about_c():
    """theta'' n^2 C = torque_z of attitude.torques.GravityGradient (C along the normal)."""
    so = hyperion()
    gg = GravityGradient(so.orbit.mu, so.orbit)
    n = so.mean_motion
    C = so.body.principal_moments[2]
    rng = np.random.default_rng(7)
    for _ in range(5):
        M, theta = rng.uniform(0, 2 * math.pi), rng.uniform(-3, 3)
        t = M / n
        q = so.initial_state(theta, 1.0).attitude.as_quat()
        torque = gg(t, q, [0.0, 0.0, n], so.body)
        acc = planar_rhs(M, theta, 1.0, so.omega0, so.e)[1]
        assert acc * n**2 * C == pytest.approx(torque[2], rel=1e-9)
        assert abs(torque[0]) + abs(torque[1]) < 1e-12 * abs(torque[2]) + 1e-300


def test_batch_equals_one_by_one():
    th = [0.3, -1.0, 0.8]
    w = [0.7, 1.6, 3.1]
    batch = stroboscopic_map(0.89, 0.1, th, w, 4, lyapunov=False, rtol=1e-12)
    for i in range(3):
        one = stroboscopic_map(0.89, 0.1, [th[i]], [w[i]], 4, lyapunov=False, rtol=1e-12)
        np.testing.assert_allclose(batch["rate"][i], one["rate"][0], rtol=0, atol=1e-8)


def test_periodic_orbit_is_a_fixed_point_and_area_preserving():
    th, w, mono = periodic_orbit(0.6313, 0.0151, 1, 1)
    assert np.linalg.det(mono) == pytest.approx(1.0, abs=1e-9)   # Liouville
    out = stroboscopic_map(0.6313, 0.0151, [th], [w], 3, lyapunov=False, rtol=1e-12)
    np.testing.assert_allclose(out["rate"][0], w, atol=1e-9)
    np.testing.assert_allclose(out["angle"][0], th, atol=1e-9)


# --- forced libration -----------------------------------------------------------------

@pytest.mark.parametrize("omega0, e", [(0.3, 0.01), (0.6313, 0.0151), (0.6313, 0.02),
                                       (1.5, 0.02)])
def test_measured_forced_libration_matches_linear_theory(omega0, e):
    """A propagated synchronous moon (3-D, gravity gradient, DOP853): the libration in
    longitude at the orbital frequency is 2 e omega0^2/(omega0^2 - 1) sin M to 1 %."""
    orbit = att.KeplerOrbit.from_elements(mu=MARS_MU, a="9376 km", e=e)
    so = att.SpinOrbit.from_omega0(omega0, orbit)
    times = np.linspace(0.0, 2 * orbit.period, 2 * 32 + 1)
    m = measure_libration(so.propagate(times), orbit)
    linear = forced_libration_amplitude(omega0, e)
    assert m.signed_amplitude == pytest.approx(linear, rel=0.01)
    assert m.amplitude == pytest.approx(so.forced_libration(), rel=0.01)
    # started on the periodic orbit: no free libration left for the fit to miss
    assert m.residual_rms < 1e-3 * m.amplitude


def test_measurement_sees_an_orbit_that_does_not_start_at_periapsis():
    orbit = att.KeplerOrbit.from_elements(mu=MARS_MU, a="9376 km", e=0.02, argp="40 deg",
                                          mean_anomaly="100 deg")
    so = att.SpinOrbit.from_omega0(0.6, orbit)
    times = np.linspace(0.0, 2 * orbit.period, 2 * 32 + 1)
    m = measure_libration(so.propagate(times), orbit)
    assert m.signed_amplitude == pytest.approx(forced_libration_amplitude(0.6, 0.02),
                                               rel=0.01)


def test_circular_orbit_control_has_no_forced_libration():
    orbit = att.KeplerOrbit.from_elements(mu=MARS_MU, a="9376 km", e=0.0)
    so = att.SpinOrbit.from_omega0(0.6313, orbit)
    times = np.linspace(0.0, 2 * orbit.period, 2 * 32 + 1)
    eph = so.propagate(times)
    assert measure_libration(eph, orbit).amplitude < 1e-9
    assert mean_spin_resonance(eph, orbit)[0] == "1:1"


def test_a_mercury_like_3_2_lock_is_recognised():
    """The 3:2 periodic orbit (planar Newton) propagated in 3-D keeps a mean spin of 1.5 n
    and a librating angle theta - 1.5 M: the [expect] resonance reads "3:2"."""
    orbit = att.KeplerOrbit(mu=1.0, a=1.0, e=0.2)
    so = att.SpinOrbit.from_omega0(0.2, orbit)
    eph = so.propagate(np.linspace(0.0, 4 * math.pi, 65), so.locked_state(3, 2))
    name, rate = mean_spin_resonance(eph, orbit)
    assert name == "3:2" and rate == pytest.approx(1.5, abs=1e-9)


def test_linear_theory_diverges_at_resonance():
    with pytest.raises(SpinOrbitError, match="omega0 = n"):
        forced_libration_amplitude(1.0, 0.01)


@pytest.mark.parametrize("name, published, tolerance", [
    ("phobos_libration", 1.14, 0.1),        # Willner et al. 2014 (deg)
    ("epimetheus_libration", 5.9, 1.2),      # Tiscareno, Thomas & Burns 2009
    ("synchronous_lock", 0.0, 1e-6),         # control
])
def test_published_anchors_from_the_scenarios(name, published, tolerance):
    """The scenario files' own run (without the chaos classification): the measured
    libration is within the published value and uncertainty, the state is 1:1."""
    sc = load_scenario(ROOT / "scenarios" / f"{name}.toml")
    eph = att.propagate(sc.body, sc.state, sc.times, torques=list(sc.torques),
                        method="integrator", rtol=1e-12)
    got = expectation_values(sc, eph)
    assert got["resonance"] == "1:1"
    assert abs(got["libration_amplitude"] - published) <= tolerance


# --- 3-D stability ------------------------------------------------------------------------

def test_hyperion_synchronous_state_is_attitude_unstable_phobos_is_not():
    """WPM 1984: Hyperion's synchronous state is stable in the plane and unstable to
    tilts of the spin axis.  The in-plane multipliers of the planar tangent equations
    reappear among those of the 3-D propagation; all come in reciprocal pairs."""
    st = hyperion().stability()
    assert st.planar_stable and not st.stable
    assert st.growth_per_orbit > 1.5
    for lam in st.planar_multipliers:
        assert np.min(np.abs(st.multipliers - lam)) < 1e-6
    mags = np.sort(np.abs(st.multipliers))
    np.testing.assert_allclose(mags * mags[::-1], 1.0, atol=1e-6)
    # Phobos as the homogeneous ellipsoid of scenarios/phobos_libration.toml (3-D
    # stability needs all three moments: a body with the same omega0 but other moments,
    # att.SpinOrbit.from_omega0(0.6313, ...), has out-of-plane multipliers near -1 pushed
    # off the unit circle by 3 %: a narrow parametric (period-doubling) resonance)
    sc = load_scenario(ROOT / "scenarios" / "phobos_libration.toml")
    phobos = att.SpinOrbit(sc.body, sc.torques[0].orbit).stability()
    assert phobos.stable and phobos.planar_stable
    np.testing.assert_allclose(np.abs(phobos.multipliers), 1.0, atol=1e-6)


# --- surface of section -----------------------------------------------------------------

INSIDE = [(80.0, 1.0), (-60.0, 1.5), (30.0, 2.0), (-20.0, 1.2)]     # WPM's chaotic sea
OUTSIDE = [(0.0, 3.3), (10.0, 0.6), (-45.0, 0.0)]   # rotation above, 1:1 island, below


def test_hyperion_section_chaotic_zone_where_wpm_show_it():
    so = hyperion()
    pts = INSIDE + OUTSIDE
    sec = so.surface_of_section([math.radians(a) for a, _ in pts], [r for _, r in pts],
                                n_orbits=40)
    assert sec.sizes == {"initial": len(pts), "orbit": 41}
    verdict = sec["chaotic"].values
    assert verdict[: len(INSIDE)].all()
    assert not verdict[len(INSIDE):].any()
    # the regular ones stay on their curves: the 1:1 island point never leaves the island
    island = sec["rate"].values[len(INSIDE) + 1]
    assert island.min() > 0.3 and island.max() < 1.05
    assert np.all(np.abs(sec["angle"].values) <= math.pi / 2)


def test_batch_verdict_agrees_with_lyapunov_py_on_the_3d_problem():
    """lyapunov.py's test on the 3-D propagation (gravity gradient, planar start) calls the
    same chaotic-sea point chaotic, with a comparable exponent per orbit."""
    so = hyperion()
    a, r = INSIDE[0]
    res = lyapunov_exponent(so.body, so.initial_state(math.radians(a), r), [so.torque()],
                            10 * so.orbit.period, intervals=10)
    sec = so.surface_of_section([math.radians(a)], [r], n_orbits=10)
    assert res.chaotic and bool(sec["chaotic"][0])
    per_orbit = res.exponent * so.orbit.period
    batch = float(sec["lyapunov_exponent"][0]) * so.orbit.period
    assert 0.5 < per_orbit / batch < 2.0


# --- despinning -----------------------------------------------------------------------

def test_despinning_time_follows_gladman_et_al():
    kw = dict(spin_rate="2 rev/d", semi_major_axis="9376 km", primary_mass=6.417e23,
              mass=1.0659e16, radius="11.1 km")
    t = despinning_time(**kw)
    k2 = love_number_k2(mass=1.0659e16, radius=11100.0)
    G = 6.67430e-11
    by_hand = (4 * math.pi / 86400) * 9376e3**6 * 0.4 * 1.0659e16 * 11100.0**2 * 100 / (
        3 * G * 6.417e23**2 * k2 * 11100.0**5)
    assert t == pytest.approx(by_hand, rel=1e-12)
    assert despinning_time(**{**kw, "semi_major_axis": 2 * 9376e3}) == pytest.approx(
        64 * t, rel=1e-12)
    # a small rigid body: k2 -> 3 rho g R / (19 mu_r)
    rho = 1.0659e16 / (4 / 3 * math.pi * 11100.0**3)
    g = G * 1.0659e16 / 11100.0**2
    assert k2 == pytest.approx(3 * rho * g * 11100.0 / (19 * 3e10), rel=1e-5)
    with pytest.raises(SpinOrbitError, match="radius"):
        despinning_time(**{**kw, "radius": -1.0})


# --- scenario keys and the command line ----------------------------------------------------

def test_expect_and_section_tables_are_validated():
    assert parse_expect("resonance", "3:2")["expected"] == "3:2"
    with pytest.raises(SpinOrbitError, match="p:q"):
        parse_expect("resonance", "synchronous")
    with pytest.raises(SpinOrbitError, match="exactly one of rel_tol, abs_tol"):
        parse_expect("libration_amplitude", {"value": 1.0, "unit": "deg"})
    with pytest.raises(SpinOrbitError, match="section.rates.count"):
        parse_section({"angles": [0.0], "rates": {"min": 0, "max": 1, "count": 0}})
    with pytest.raises(SpinOrbitError, match="section.orbits: unknown key"):
        parse_section({"angles": [0.0], "rates": [1.0], "orbits": 3})


def _section_scenario(tmp_path, extra="", section=True) -> Path:
    text = (ROOT / "scenarios" / "hyperion_section.toml").read_text()
    if not section:
        text = text.split("\n[section]\n")[0]
    else:
        text = text.replace("count = 20, unit", "count = 3, unit").replace(
            "count = 20 }", "count = 2 }").replace("n_orbits = 200", "n_orbits = 5")
    path = tmp_path / "sec.toml"
    path.write_text(text + extra)
    return path


def test_cli_section_writes_netcdf_and_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    path = _section_scenario(tmp_path)
    out = tmp_path / "s.nc"
    assert main(["section", str(path), "-o", str(out), "--plot"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.sizes == {"initial": 6, "orbit": 6}
        assert set(ds["chaotic"].values.tolist()) <= {0, 1}
        assert ds["angle"].attrs["units"] == "rad"
    assert out.with_suffix(".png").stat().st_size > 1000
    assert "6 initial conditions x 5 orbits" in capsys.readouterr().out
    assert not list(tmp_path.glob(".*.tmp"))                       # atomic write


def test_cli_section_bad_input_exits_2(tmp_path, capsys):
    assert main(["section", str(_section_scenario(tmp_path, section=False))]) == 2
    assert "no [section] table" in capsys.readouterr().err
    bad = _section_scenario(tmp_path, extra="")
    bad.write_text(bad.read_text().replace("n_orbits = 5", "n_orbits = -5"))
    assert main(["section", str(bad)]) == 2
    assert "section.n_orbits" in capsys.readouterr().err


def test_spin_orbit_expectations_are_not_for_ensembles():
    with pytest.raises(SpinOrbitError, match="expect.resonance: not for"):
        load_tables({}, body=None, torques=(), expect=(Expectation.exact("resonance", "1:1"),),
                    ensemble=object())


def test_spin_orbit_expectations_need_a_keplerian_gravity_gradient(tmp_path):
    text = (ROOT / "scenarios" / "phobos_libration.toml").read_text()
    text = text.split("[[torques]]")[0] + text.split("[expect]")[1].join(["[expect]", ""])
    path = tmp_path / "no_torque.toml"
    path.write_text(text.replace("method = \"integrator\"\nrtol = 1e-12\n", ""))
    with pytest.raises(ScenarioError, match="gravity_gradient"):
        load_scenario(path)
