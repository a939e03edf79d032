"""The checks of a scenario's ``[expect]`` table against what its run gave: the regime,
the periods, the conservation figures, the nutation range, the dataset variables, the
regime fractions of an ensemble, the spin trend and the spin-orbit keys.

:mod:`attitude.app.scenario` parses the table into :class:`~attitude.foundations.
expectation.Expectation` s (``Scenario.expect``) and runs the scenario; this module
compares.
"""

from __future__ import annotations

import numpy as np
from astropy import units as u

from ..analysis.diagnostics import DIAGNOSTIC_VARIABLES, SCALAR_DIAGNOSTICS
from ..foundations.expectation import Expectation
from ..model.regimes import PERIOD_KEYS
from .scenario_spec import SPIN_EXPECT_KEYS

__all__ = ["BASE_VARIABLES", "known_variables", "needs_dataset", "check_expectations"]


#: Variables of the base ephemeris dataset (docs/states_and_ephemerides.md) and their units.
BASE_VARIABLES = {"quaternion": "1", "angular_velocity": "rad s-1",
                  "angular_momentum": "kg m2 s-1", "kinetic_energy": "J"}


def known_variables() -> dict[str, tuple[str, bool]]:
    """Variables ``[expect.variables]`` may name: ``{name: (units, is_time_series)}``.

    The base dataset (``quaternion``, ``angular_velocity``, ``angular_momentum``,
    ``kinetic_energy``), the time series of :func:`attitude.analysis.diagnostics.add_diagnostics`
    (:data:`~attitude.analysis.diagnostics.DIAGNOSTIC_VARIABLES`) and its scalars (conservation
    figures, ``attitude_noise``, measured periods ``period_<key>`` and their
    ``period_<key>_uncertainty``).

    Examples
    --------
    >>> variables = known_variables()
    >>> variables["kinetic_energy"], variables["period_polhode"]   # (units, time series?)
    (('J', True), ('s', False))
    """
    out = {k: (v, True) for k, v in BASE_VARIABLES.items()}
    out.update({k: (v[0], True) for k, v in DIAGNOSTIC_VARIABLES.items()})
    out.update({name: (units, False) for name, units, _ in SCALAR_DIAGNOSTICS.values()})
    for key in PERIOD_KEYS:
        out[f"period_{key}"] = ("s", False)
        out[f"period_{key}_uncertainty"] = ("s", False)
    return out


def needs_dataset(scenario) -> str | None:
    """Whether checking the expectations needs :func:`add_diagnostics` of the run:
    ``None`` (no), ``"base"`` (base variables only), ``"diagnostics"`` or ``"periods"``.

    Examples
    --------
    >>> from attitude.app.scenario import load_scenario
    >>> needs_dataset(load_scenario("scenarios/dzhanibekov.toml")) is None   # regime, periods
    True
    """
    need = None
    base = set(BASE_VARIABLES)
    for e in scenario.expect:
        variable = e.option("variable")
        if e.key.startswith("nutation_range.") and scenario.torques:
            need = need or "diagnostics"
        elif variable is not None:
            if variable.startswith("period_"):
                return "periods"
            if variable not in base:
                need = "diagnostics"
            elif need is None:
                need = "base"
    return need


def _reduce(data: np.ndarray, at: str | None) -> float:
    if at is None:
        return float(data)
    if at == "start":
        return float(data[0])
    if at == "end":
        return float(data[-1])
    return float(getattr(np, {"max": "nanmax", "min": "nanmin", "mean": "nanmean"}[at])(data))


def _variable_value(dataset, e: Expectation) -> float | None:
    """The reduced value of one ``[expect.variables]`` entry in its expected unit."""
    if dataset is None or e.option("variable") not in dataset:
        return None
    var = dataset[e.option("variable")]
    data = np.asarray(var.values, dtype=float)
    comp = e.option("component")
    if comp == "norm":
        data = np.linalg.norm(data, axis=-1)
    elif comp is not None:
        data = data[..., comp]
    got = _reduce(data, e.option("at"))
    units = var.attrs.get("units", "1")
    return float((got * u.Unit(units)).to_value(e.unit))


def check_expectations(scenario, regime: str | None, periods: dict,
                       conservation: dict, *, diagnosis=None, dataset=None,
                       fractions: dict | None = None,
                       spinorbit: dict | None = None, spin=None) -> list[dict]:
    """Compare the parsed ``[expect]`` entries with what the run gave.

    ``diagnosis`` (:func:`attitude.diagnose` of the initial state) gives the nutation range
    of a torque-free run; ``dataset`` (the run's ephemeris dataset, with the variables of
    :func:`attitude.analysis.diagnostics.add_diagnostics` when :func:`needs_dataset` says so) the
    nutation range of a run with torques (extremes of ``nutation_angle`` over the run) and
    the ``[expect.variables]`` values; ``spin`` (:class:`attitude.analysis.spindown.SpinTrend`)
    the spin period and its trend.  Without them those entries get ``got = None``
    (a failure).

    Examples
    --------
    >>> from attitude.app.scenario import load_scenario
    >>> sc = load_scenario("scenarios/dzhanibekov.toml")    # expects SAM, polhode 3.3108 s
    >>> drift = {"angular_momentum_rel_drift": 1e-15, "energy_rel_drift": 1e-15}
    >>> results = check_expectations(sc, "SAM", {"polhode": 3.5}, drift)
    >>> [r["key"] for r in results if not r["ok"]]            # 3.5 s is off by 6 %
    ['polhode']
    >>> len(results)
    4
    >>> round(results[1]["tolerance"], 8)                       # rel_tol 1e-4 of 3.3108 s
    0.00033108
    """
    results = []
    for e in scenario.expect:
        key = e.key
        if key == "resonance":                        # spin-orbit wing: a "p:q" string
            got = (spinorbit or {}).get(key)
        elif key == "regime":
            got = regime
        elif key in PERIOD_KEYS:
            got = periods.get(key)
            got = None if got is None else got / u.Unit(e.unit).to(u.s)
        elif key.startswith("nutation_range."):
            got = _nutation_bound(scenario, key.rsplit(".", 1)[1], diagnosis, dataset)
            got = None if got is None else float((got * u.rad).to_value(e.unit))
        elif key.startswith("variables."):
            got = _variable_value(dataset, e)
        elif key.startswith("regime_fractions."):
            got = None if fractions is None else fractions.get(key.split(".", 1)[1], 0.0)
        elif key == "libration_amplitude":            # spin-orbit wing
            got = (spinorbit or {}).get(key)
        elif key in SPIN_EXPECT_KEYS:                 # issue 17: attitude.spindown
            got = None if spin is None else _spin_value(spin, e)
        else:                                         # a conservation bound
            got = conservation[key]
        results.append(e.check(got))
    return results


def _spin_value(spin, e: Expectation) -> float:
    """The spin period (at ``start`` / ``end``), its trend or its e-folding time, in the
    expectation's unit."""
    if e.key == "spin_period":
        seconds = spin.period_start if e.option("at") == "start" else spin.period_end
        return float((seconds * u.s).to_value(e.unit))
    if e.key == "spin_period_trend":
        return float((spin.trend * u.dimensionless_unscaled).to_value(e.unit))
    return float((spin.efolding * u.s).to_value(e.unit))


def _nutation_bound(scenario, which: str, diagnosis, dataset) -> float | None:
    """theta_min / theta_max, rad: analytic (torque-free) or over the run (torques)."""
    if not scenario.torques:
        if diagnosis is None or diagnosis.nutation_range is None:
            return None
        return float(diagnosis.nutation_range[0 if which == "min" else 1])
    if dataset is None or "nutation_angle" not in dataset:
        return None
    return _reduce(np.asarray(dataset["nutation_angle"].values, dtype=float), which)
