"""Ensembles of binaries (attitude.binary.ensembles): the same outcomes as member-by-member
runs, bad and failing members isolated, the regime fractions, dask."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import attitude as att
from attitude.binary.ensembles import STATUS_FAILED, STATUS_INVALID, STATUS_OK, sample_dart

PERIOD = 11.92 * 3600.0
TIMES = np.arange(0.0, 2.8 * PERIOD, 600.0)
STEP = 120.0


def _by_hand(system, state, impulses):
    eph = att.propagate(system, state, TIMES, step=STEP, events=impulses)
    t_imp = [i.seconds_after(state.epoch) for i in impulses]
    d = att.binary.diagnose(eph, impulses=t_imp)
    change = att.binary.period_change(eph, t_imp[0]).change
    return d, change


def _spinning(member):
    """The member with its secondary spinning at five times the synchronous rate."""
    system, state, impulses, inputs = member
    state = att.BinaryState(state.epoch, state.position, state.velocity,
                            state.primary_attitude, state.primary_omega,
                            state.secondary_attitude, 5 * np.asarray(state.secondary_omega))
    return system, state, impulses, inputs


def test_ensemble_equals_member_by_member_runs():
    members = sample_dart(3, rng=7)
    ds = att.binary.ensemble(members, TIMES, step=STEP)
    assert ds.sizes["member"] == 3 and ds.status.values.tolist() == [STATUS_OK] * 3
    for i, (system, state, impulses, inputs) in enumerate(members):
        d, change = _by_hand(system, state, impulses)
        assert ds.orbit_period.values[i] == d.orbit_period
        assert ds.period_change.values[i] == change
        assert ds.libration_amplitude.values[i] == d.libration_amplitude
        assert ds.secondary_regime.values[i] == d.secondary_regime
        assert ds.beta.values[i] == inputs["beta"]
    # the DART result: beta ~ 3.6 shortens the orbit by about half an hour (Thomas et
    # al. 2023: -33 min), more for a larger beta
    assert np.all((ds.period_change.values / 60 > -45) & (ds.period_change.values / 60 < -25))
    order = np.argsort(ds.beta.values)
    assert np.all(np.diff(ds.period_change.values[order]) < 0)


def test_bad_and_failing_members_do_not_stop_the_others():
    good = sample_dart(2, rng=2)
    system, state, impulses, _ = good[0]
    crashed = att.BinaryState(state.epoch, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0],   # falls in
                              Rotation.identity(), [0, 0, 0], Rotation.identity(), [0, 0, 0])
    members = [good[0], (None, state), (system, state, ["not an impulse"]),
               (system, crashed), good[1]]
    ds = att.binary.ensemble(members, TIMES, step=STEP)
    assert ds.status.values.tolist() == [STATUS_OK, STATUS_INVALID, STATUS_INVALID,
                                         STATUS_FAILED, STATUS_OK]
    assert "BinarySystem" in ds.message.values[1] and "Impulse" in ds.message.values[2]
    alone = att.binary.ensemble([good[1]], TIMES, step=STEP)
    assert ds.period_change.values[4] == alone.period_change.values[0]
    assert math.isnan(ds.orbit_period.values[1])


def test_regime_fractions_add_up_to_one():
    members = sample_dart(3, rng=5)
    members[1] = _spinning(members[1])
    ds = att.binary.ensemble(members, TIMES, step=STEP)
    fractions = ds.attrs["regime_fractions"]
    assert fractions == {"librating": 2 / 3, "circulating": 1 / 3}
    assert math.fsum(fractions.values()) == 1.0


@pytest.mark.slow          # a two-worker LocalCluster: ~10 s to start on a busy machine
def test_on_a_dask_local_cluster():
    pytest.importorskip("distributed")
    from attitude.propagation.cluster import local_cluster

    members = sample_dart(4, rng=11)
    members[2] = (None, members[2][1])
    here = att.binary.ensemble(members, TIMES, step=STEP)
    with local_cluster(2) as client:
        there = att.binary.ensemble(members, TIMES, step=STEP, client=client, chunk_size=1)
    assert there.status.values.tolist() == [0, 0, 1, 0]
    for key in ("orbit_period", "period_change", "libration_amplitude"):
        np.testing.assert_array_equal(there[key].values, here[key].values)
    assert there.attrs["regime_fractions"] == here.attrs["regime_fractions"]


SCENARIO = f'''
[scenario]
name = "DART family"

[binary]
epoch = "2022-09-26T00:00:00"
duration = "{2.8 * PERIOD} s"
output_step = "10 min"
step = "{STEP} s"
synchronous = true

[binary.primary]
primitive = "ellipsoid"
mass = "5.282e11 kg"
semi_axes = [394.0, 394.0, 290.0]
spin_period = "2.26 h"

[binary.secondary]
primitive = "ellipsoid"
mass = "4.3e9 kg"
semi_axes = [89.5, 84.5, 57.5]

[binary.orbit]
semi_major_axis = "1.19 km"
circular = true

[[binary.impulse]]
time = "{1.5 * PERIOD} s"           # Dimorphos near -x, moving -y: a head-on hit
beta = 3.61
impactor_mass = "580 kg"
impactor_velocity = [0.0, 5546.3, -2645.5]

[binary.ensemble]
n = 4
seed = 3
sigma = {{ "impulse.beta" = 0.2, "primary.mass" = "1e10 kg", "secondary.semi_axes" = 1.5 }}

[expect.regime_fractions]
librating = {{ value = 1.0, abs_tol = 1e-12 }}
'''


def test_scenario_ensemble_runs_with_attitude_run(tmp_path, capsys):
    import json

    from attitude.app.cli import main
    from attitude.binary.config import load_binary, run_binary

    path = tmp_path / "family.toml"
    path.write_text(SCENARIO)
    run = run_binary(load_binary(path), write_outputs=False)
    ds = run.ensemble
    assert ds.status.values.tolist() == [0] * 4 and run.ok
    assert sorted(ds.attrs["inputs"]) == ["impulse_beta", "primary_mass",
                                          "secondary_semi_axes_0", "secondary_semi_axes_1",
                                          "secondary_semi_axes_2"]
    assert np.all((ds.period_change.values / 60 > -45) & (ds.period_change.values / 60 < -25))
    # the CLI: summary, report, netCDF; exit 0 (expectations met)
    code = main(["run", str(path), "-o", str(tmp_path / "family.nc"),
                 "--report", str(tmp_path / "r.json")])
    assert code == 0, capsys.readouterr()
    report = json.loads((tmp_path / "r.json").read_text())
    assert report["status"]["ok"] == 4 and report["regime_fractions"] == {"librating": 1.0}
    import xarray as xr
    with xr.open_dataset(tmp_path / "family.nc") as back:
        np.testing.assert_array_equal(back.period_change.values, ds.period_change.values)


@pytest.mark.parametrize("edit, key", [
    ('sigma = { "impulse.beta" = 0.2', 'sigma = { "orbit.inclination" = 0.2'),
    ("[expect.regime_fractions]", "[expect.orbit_period]\nvalue = 1.0\nabs_tol = 1.0\n"
                                  "[expect.regime_fractions]"),
])
def test_scenario_ensemble_bad_input(tmp_path, edit, key):
    from attitude.binary.config import load_binary
    from attitude.foundations.errors import ScenarioError

    path = tmp_path / "family.toml"
    path.write_text(SCENARIO.replace(edit, key))
    with pytest.raises(ScenarioError):
        load_binary(path)


def test_an_impossible_draw_is_bad_input_and_chaos_adds_the_exponent():
    members = sample_dart(2, rng=4, primary_mass=(-1.0, 0.0))      # no mass: bad input
    assert isinstance(members[0][0], Exception)
    ds = att.binary.ensemble(members, TIMES, step=STEP)
    assert ds.status.values.tolist() == [STATUS_INVALID] * 2 and ds.attrs[
        "regime_fractions"] == {}
    assert "lyapunov_exponent" not in ds
    one = sample_dart(1, rng=4)
    short = TIMES[TIMES <= 2.0 * PERIOD]
    ds = att.binary.ensemble(one, short, step=STEP, chaos=True)
    system, state, impulses, _ = one[0]
    eph = att.propagate(system, state, short, step=STEP, events=impulses)
    d = att.binary.diagnose(eph, impulses=[impulses[0].seconds_after(state.epoch)],
                            chaos=True, system=system)
    assert ds.lyapunov_exponent.values[0] == d.lyapunov_exponent


def test_a_family_runs_at_once_with_the_outcomes_of_its_members_alone():
    """Members of one family (one order and G, the impact at one time) run together
    (propagate_family: the LGVI vectorised over the members); each outcome equals the
    member's own run to the round-off of the vectorised sums (einsum over members), far
    below the LGVI's own error: 1e-9 relative on the periods."""
    from attitude.binary.propagate import propagate_family

    base = sample_dart(1, rng=7)[0]
    system, state, impulses, _ = base
    members = []
    for scale in (0.97, 1.0, 1.04):
        secondary = att.RigidBody.from_mass_properties(att.MassProperties.solid_ellipsoid(
            system.secondary.mass, scale * system.secondary.distribution.semi_axes))
        members.append((att.BinarySystem(system.primary, secondary, order=system.order,
                                         G=system.G), state, impulses))
    ds = att.binary.ensemble(members, TIMES, step=STEP)
    together = propagate_family([m[0] for m in members], [state] * 3, TIMES, step=STEP,
                                events=[impulses] * 3)
    for i, (s, st, imp) in enumerate(members):
        d, change = _by_hand(s, st, imp)
        assert ds.orbit_period.values[i] == pytest.approx(d.orbit_period, rel=1e-9)
        assert ds.period_change.values[i] == pytest.approx(change, rel=1e-9)
        alone = att.propagate(s, st, TIMES, step=STEP, events=imp).dataset
        np.testing.assert_allclose(together[i].dataset.relative_position.values,
                                   alone.relative_position.values, rtol=0, atol=1e-9 * 1190)
