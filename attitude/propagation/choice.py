"""The method ``propagate`` runs with torques and no ``method=``: the cheaper of the compiled
DOP853 and the compiled splitting, each set to a default accuracy.

**The default accuracy** is :data:`AUTO_ACCURACY`, an attitude error of ~1e-8 rad over
the run (a global error, not a per-step tolerance), from which each method's setting
follows through an error model fitted on gravity-gradient runs
(``benchmarks/spin_crossover.py`` and case A of ``benchmarks/perturbed.py``; measured
values in docs/integrators.md, "The automatic choice"):

* DOP853 (``method="integrator"``): its error grows about as ``rtol N^1.8`` with the
  number of turns ``N = (|omega| + omega_M) span / 2 pi`` (``omega_M``: the torques'
  own rate, :meth:`~attitude.model.torques.TorqueModel.characteristic_rate`): the phase
  error of a non-symplectic method grows quadratically.  ``rtol = AUTO_ACCURACY /
  (0.25 N^1.8)``, kept within :data:`RTOL_RANGE`, the smallest over a batch's bodies.
* the splitting (order 4, fixed step): the step rule's step ``h_rule``
  (:func:`attitude.propagation.stepsize.choose_step`, ``N = 300`` steps per period of
  the torque's pace) errs by about :data:`SPLITTING_RULE_ERROR` over such runs and the
  error grows as ``h^4``, so ``h = h_rule (AUTO_ACCURACY / SPLITTING_RULE_ERROR)^(1/4)``
  (6.7 ``h_rule``), and at most ``1 / nu`` (``nu``: how fast the torque turns along the
  free motion, at most the spin): the kicks must sample the torque's turning, beyond
  ``h nu ~ 1.3`` the error jumps by orders of magnitude.

**The cost model** counts DOP853 steps (12 right-hand sides each): DOP853 takes
``0.18 rtol^(-1/8)`` steps per radian of ``(|omega| + omega_M) t`` (the step counts of
scipy's DOP853, which the compiled one reproduces), plus a quarter step for each step
holding an output (its three extra dense-output stages); a splitting step costs
:data:`SPLITTING_STEP_COST` DOP853 steps and an output inside a step one more step (a
partial step from the step's start).  The cheaper estimate wins; the run records which
method ran and why (the ephemeris attributes ``method`` and ``method_reason``).

**The choice's own cost** stays small against the runs it chooses for (a compiled run of
a few milliseconds, ``benchmarks/spin_crossover.py`` times it): the spin, the torques'
own rates (``characteristic_rate``, closed forms of the models' parameters) and both
cost estimates take no propagation; the splitting's cost at ``nu = 0`` is a lower bound
(``nu`` only shortens its step).  ``nu`` is measured (a few free flows and one call of
each torque model on five states, ~1 ms in numpy; :data:`NU_MEASURE_COST`) only when
that bound is below DOP853's cost by more than the measurement costs: otherwise DOP853
runs, and the most it can lose against the splitting is what measuring would have cost.
An ensemble is judged on at most 4096 of its bodies, spread over it.

Without numba, or with a torque model that has no compiled form, there is no compiled
method to choose from: the splitting runs at its step rule, as before the choice existed
(on numpy it advances a whole batch at once).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.body import as_bodies
from ..model.torques import TorqueModel
from .compiled import NUMBA
from .compiled_torques import callback_model
from .kicks import System, torque_terms
from .stepsize import STEPS_PER_PERIOD, own_rates, torque_rates

__all__ = []

#: Default accuracy of the automatic choice: attitude error over the run, rad.
AUTO_ACCURACY = 1e-8
#: DOP853's rtol in the automatic choice stays within this range.
RTOL_RANGE = (1e-13, 1e-6)
#: DOP853's error model ``err = C rtol N^P`` (``N`` turns of ``|omega| + omega_M``).
DOP853_ERROR = (0.25, 1.8)
#: DOP853 steps per radian of ``(|omega| + omega_M) t``, times ``rtol^(1/8)``.
DOP853_STEPS_PER_RADIAN = 0.18
#: Attitude error of the splitting (order 4) at the step rule's step over the
#: calibration runs, rad (measured 3e-12 to 6e-11 at slow to moderate spins).
SPLITTING_RULE_ERROR = 5e-12
#: Largest ``h nu`` of the automatic splitting step.
SPLITTING_MAX_TURN = 1.0
#: Cost of one compiled splitting step (order 4: six free flows and kicks) in compiled
#: DOP853 steps, measured with gravity gradient (``benchmarks/spin_crossover.py``).
SPLITTING_STEP_COST = 1.7
#: Cost of measuring ``nu`` (a System, four free flows, one call of each torque model
#: on five states, in numpy: ~1 ms in a loop of its own, up to ~2 ms between
#: propagations, ``benchmarks/spin_crossover.py``) in compiled DOP853 steps (~10 us
#: each with gravity gradient): the lower figure, so that nu is measured when in doubt.
NU_MEASURE_COST = 50.0


@dataclass(frozen=True)
class Choice:
    """The method chosen, its setting (``rtol`` or ``step``) and the reason, with the
    estimated costs in DOP853 steps."""

    method: str
    reason: str
    rtol: float | None = None
    step: float | None = None
    cost_integrator: float = math.nan
    cost_splitting: float = math.nan


def _compiled_form_expected(terms) -> bool:
    """Whether every torque model has a compiled form (a built-in model), without
    building it (an environment table can take seconds)."""
    return all(isinstance(m, TorqueModel)
               and type(m).compiled_parameters is not TorqueModel.compiled_parameters
               for m in terms)


def _callback_only(terms) -> bool:
    """Whether one external model runs by its own ``numba_torque`` and every other has a
    compiled form: only the compiled DOP853 can call the callback
    (:func:`attitude.propagation.compiled_torques.user_torque`)."""
    user = callback_model(terms)
    return user is not None and _compiled_form_expected([m for m in terms if m is not user])


def _spans(t: np.ndarray) -> tuple[float, float]:
    """How far the outputs reach forward and backward of the state's time, s."""
    if not t.size:
        return 0.0, 0.0
    return max(0.0, float(t.max())), -min(0.0, float(t.min()))


def _off_grid(t: np.ndarray, h: float) -> int:
    """Outputs that fall inside a step of the grid ``k h`` (a partial step each)."""
    if not math.isfinite(h):
        return 0
    x = np.abs(t) / h
    return int(np.count_nonzero(np.abs(x - np.round(x)) > 1e-9 * np.maximum(x, 1.0)))


def dop853_rtol(turns: np.ndarray, accuracy: float = AUTO_ACCURACY) -> float:
    """DOP853's rtol for ``accuracy`` over ``turns`` (per body; the smallest)."""
    c, p = DOP853_ERROR
    most = max(float(np.max(turns)), 1.0)
    return min(max(accuracy / (c * most ** p), RTOL_RANGE[0]), RTOL_RANGE[1])


def splitting_step(h_rule: float, nu: float, accuracy: float = AUTO_ACCURACY) -> float:
    """The automatic splitting step, s: the rule's step scaled to ``accuracy`` (error
    ~ h^4), at most ``SPLITTING_MAX_TURN / nu``."""
    h = h_rule * (accuracy / SPLITTING_RULE_ERROR) ** 0.25
    if nu > 0:
        h = min(h, SPLITTING_MAX_TURN / nu)
    return h


def _splitting_cost(t: np.ndarray, n: int, own, rate, nu, accuracy: float):
    """``(step, cost)`` of the splitting at the step rule's ``rate`` (per body) and the
    torque's turning ``nu`` (per body), for ``n`` bodies over the outputs ``t``."""
    forward, backward = _spans(t)
    top = float(np.max(rate, initial=0.0))
    h_rule = (2.0 * math.pi / (STEPS_PER_PERIOD[4] * top)
              if top > 0 and math.isfinite(top) else math.inf)
    h = splitting_step(h_rule, float(np.max(nu, initial=0.0)), accuracy)
    steps = (math.ceil(forward / h) + math.ceil(backward / h) if math.isfinite(h) else 1)
    return h, n * SPLITTING_STEP_COST * (steps + _off_grid(t, h))


def _measured_turning(body_list, q0, w0, torques):
    """``(omega_M, nu, rate)`` per body (:func:`attitude.propagation.stepsize.torque_rates`:
    ``nu`` measured along the free flow)."""
    system = System(body_list, torques)
    q_p, w_p = system.to_principal(q0, w0)
    return torque_rates(system, q_p, w_p, 4, 0.0, True)


def choose_method(body_list, q0: np.ndarray, w0: np.ndarray, t: np.ndarray, torques,
                  accuracy: float = AUTO_ACCURACY) -> Choice:
    """The automatic method for bodies ``body_list`` at ``(q0 (N, 4), w0 (N, 3))``
    (body frames) over the outputs ``t`` (s from the state's time) under ``torques``."""
    body_list = list(body_list)
    n = len(body_list)
    q0 = np.asarray(q0, dtype=float)
    w0 = np.asarray(w0, dtype=float)
    t = np.asarray(t, dtype=float)
    terms = torque_terms(torques)
    compiled = NUMBA and _compiled_form_expected(terms)
    # the cheap part, without propagating: the spin (a norm: the same in body and
    # principal axes), the torques' own rates, DOP853's cost and the splitting's at
    # nu = 0, a lower bound (nu only shortens its step)
    spin = np.sqrt(np.sum(w0 * w0, axis=1))
    body_arg = body_list[0] if n == 1 else as_bodies(body_list)[0]
    own = np.zeros(n)
    for model in terms:
        own = np.maximum(own, own_rates(model, body_arg, n, 0.0, q0, w0))
    forward, backward = _spans(t)
    turns = (spin + own) * (forward + backward) / (2.0 * math.pi)
    rtol = dop853_rtol(turns, accuracy)
    steps_dop = DOP853_STEPS_PER_RADIAN * rtol ** -0.125 * 2.0 * math.pi * turns + 1.0
    ordered = np.sort(t)                 # distinct outputs (np.unique costs more)
    outputs = int(np.count_nonzero(ordered[1:] != ordered[:-1])) + 1 if t.size else 0
    cost_dop = float(np.sum(steps_dop + 0.25 * np.minimum(outputs, steps_dop)))
    step, cost_split = _splitting_cost(t, n, own, own, 0.0, accuracy)
    pace = (f"spin {float(spin.max()):.3g} rad/s against the torque's pace "
            f"{float(own.max()):.3g} rad/s")
    dop853 = f"compiled DOP853 at rtol {rtol:.2g} (~{cost_dop:.3g} step-costs)"

    if NUMBA and not compiled and _callback_only(terms):
        return Choice("integrator", f"{pace}: {dop853}: a torque with its own numba "
                      "function (numba_torque) runs on the compiled DOP853 only", rtol=rtol,
                      cost_integrator=cost_dop, cost_splitting=cost_split)
    if compiled and cost_dop <= cost_split + NU_MEASURE_COST:
        # nu is not measured: the splitting cannot be cheaper, or not by more than
        # measuring nu would cost
        if cost_dop <= cost_split:
            why = (f"is cheaper than the splitting at step {step:.3g} s or less "
                   f"(~{cost_split:.3g} or more) for ~{accuracy:g} rad")
        else:
            why = (f"for ~{accuracy:g} rad; the splitting (at step {step:.3g} s or less, "
                   f"~{cost_split:.3g} or more) could save at most "
                   f"~{cost_dop - cost_split:.3g}, less than measuring how fast the torque "
                   f"turns along the free motion would cost (~{NU_MEASURE_COST:g})")
        return Choice("integrator", f"{pace}: {dop853} {why}", rtol=rtol,
                      cost_integrator=cost_dop, cost_splitting=cost_split)
    own, nu, rate = _measured_turning(body_list, q0, w0, torques)
    step, cost_split = _splitting_cost(t, n, own, rate, nu, accuracy)
    if not compiled:
        why = ("numba is not installed" if not NUMBA
               else "a torque model has no compiled form")
        return Choice("splitting", f"{why}: the splitting (numpy path) at its step rule, "
                      "no compiled method to choose from", cost_integrator=cost_dop,
                      cost_splitting=cost_split)
    if cost_dop <= cost_split:
        return Choice("integrator", f"{pace}: {dop853} is cheaper than the splitting at "
                      f"step {step:.3g} s (~{cost_split:.3g}) for ~{accuracy:g} rad",
                      rtol=rtol, cost_integrator=cost_dop, cost_splitting=cost_split)
    return Choice("splitting", f"{pace}: the compiled splitting at step {step:.3g} s "
                  f"(~{cost_split:.3g} step-costs) is cheaper than DOP853 at rtol "
                  f"{rtol:.2g} (~{cost_dop:.3g}) for ~{accuracy:g} rad",
                  # no torque rate at all: the step rule's own (one free flow) step
                  step=step if math.isfinite(step) else None,
                  cost_integrator=cost_dop, cost_splitting=cost_split)
