"""Coupled consolidation against the closed forms and MOOSE: Terzaghi (peer case A) with
EFG and every FEM pair, Mandel's centre pressure and the Mandel-Cryer effect.
"""

import itertools

import numpy as np
import pandas as pd

from soilwater.case.loader import load_case
from soilwater.references.closed_forms import undrained_pressure
from soilwater.studies.harness.metrics import mandel_errors, moose_errors, terzaghi_errors
from soilwater.studies.harness.moose import moose_terzaghi
from soilwater.studies.harness.runs import FEM_METHODS, solved
from soilwater.methods import EFG_METHODS


def fem_terzaghi(methods=FEM_METHODS, moose=None):
    """Terzaghi with every FEM pair on MOOSE's steps, and on steps capped at 0.01.

    Returns
    -------
    pandas.DataFrame
        ``method, steps`` (``moose`` or ``dt<=0.01``), the errors of
        :func:`soilwater.studies.harness.metrics.terzaghi_errors` and, on MOOSE's steps
        with ``moose`` given, those of
        :func:`soilwater.studies.harness.metrics.moose_errors`.
    """
    steps = {"moose": (), "dt<=0.01": ("time.dt_max=0.01", "time.end=2.0")}
    settings = list(itertools.product(steps, methods))
    results = solved([("terzaghi", steps[label], method) for label, method in settings])
    rows = []
    for (label, method), result in zip(settings, results):
        errors = terzaghi_errors(result)
        row = {"method": method, "steps": label,
               "error_p0_after_0.1": max(v for k, v in errors["window_errors"].items()
                                         if not k.startswith(("0 ", "0.01 "))),
               "settlement_after_0.1": errors["settlement_error_after_0.1"],
               "overshoot": errors["overshoot"]}
        if moose is not None and label == "moose":
            row.update({f"moose_{k}": v for k, v in moose_errors(result, moose).items()})
        rows.append(row)
    return pd.DataFrame(rows)


def consolidation(methods=EFG_METHODS):
    """Terzaghi (5 x 41 nodes) and Mandel errors of EFG in each configuration
    (``efg``, the recommended, and ``efg-paper``), the case's other settings default.

    Returns
    -------
    pandas.DataFrame
        ``method, case, metric, value``.
    """
    rows = []
    for method in methods:
        terzaghi, mandel = solved([
            ("terzaghi", ("discretisation.nx=5", "discretisation.ny=41"), method),
            ("mandel", (), method)])
        terzaghi, mandel = terzaghi_errors(terzaghi), mandel_errors(mandel)
        rows += [(method, "terzaghi", f"max abs(p - p_exact) / p0, {w}", v)
                 for w, v in terzaghi.pop("window_errors").items()]
        rows += [(method, "terzaghi", k, v) for k, v in terzaghi.items()]
        rows += [(method, "mandel", k, v) for k, v in mandel.items()]
    return pd.DataFrame(rows, columns=["method", "case", "metric", "value"])


def consolidation_histories():
    """Terzaghi and Mandel pore pressures of EFG and FEM beside the closed forms.

    Returns
    -------
    terzaghi : pandas.DataFrame
        ``run, time, y, p`` (p over the undrained p0) at the probes p0..p9, for EFG
        (5 x 41 nodes), fem-q1q1 and fem-th (MOOSE's 2 x 11 vertices) and MOOSE's file.
    mandel : pandas.DataFrame
        ``run, time, p_centre, p_exact`` (over F/(2a)) for EFG, fem-th and fem-q1q1.
    """
    runs = {"EFG (5 x 41 nodes)": ("efg", ("discretisation.nx=5", "discretisation.ny=41")),
            "fem-q1q1": ("fem-q1q1", ()), "fem-th": ("fem-th", ())}
    terzaghi_runs = solved([("terzaghi", o, m) for m, o in runs.values()])
    mandel_runs = solved([("mandel", (), m) for m in ("efg", "fem-th", "fem-q1q1")])
    frames = []
    for label, result in zip(runs, terzaghi_runs):
        case, h = result.case, result.history
        p0 = _terzaghi_p0(case)
        for k in range(10):
            frames.append(pd.DataFrame({"run": label, "time": h.time, "y": float(k),
                                        "p": h[f"p_w@p{k}"] / p0}))
    moose, case = moose_terzaghi(), terzaghi_runs[1].case
    p0_unit_load = _terzaghi_p0(case) / -case.boundary.top.traction[1]  # MOOSE's load is 1
    frames += [pd.DataFrame({"run": "MOOSE Q1/Q1 (peer)", "time": moose.time, "y": float(k),
                             "p": moose[f"p{k}"] / p0_unit_load}) for k in range(10)]
    mandel_frames = []
    for label, result in zip(("EFG", "fem-th", "fem-q1q1"), mandel_runs):
        case, h = result.case, result.history
        force, a = -case.plate_force(case.times()[-1]), case.geometry.width
        mandel_frames.append(pd.DataFrame({"run": label, "time": h.time,
                                           "p_centre": h["p_w@centre"] / (force / (2 * a)),
                                           "p_exact": mandel_centre(h.time, case)}))
    return pd.concat(frames, ignore_index=True), pd.concat(mandel_frames, ignore_index=True)


def mandel_centre(times, case=None):
    """Mandel's closed-form centre pressure over F/(2a) at ``times`` [s] (built-in
    ``mandel`` case unless another is given): drawn on a grid of its own, it shows no
    kinks of the solvers' time levels."""
    from soilwater.references.closed_forms import mandel

    case = case or load_case("mandel")
    material, a = case.material(), case.geometry.width
    force = -case.plate_force(case.times()[-1])
    exact = [mandel([0.0], t, force, a, material.G, material.nu, case.fluid.mobility)[0]
             for t in np.asarray(times, float)]
    return np.array(exact) / (force / (2 * a))


def _terzaghi_p0(case):
    """Undrained pore pressure of the Terzaghi column under its load."""
    fluid = case.fluid
    return undrained_pressure(-case.boundary.top.traction[1],
                              case.material().constrained_modulus(), fluid.biot_alpha,
                              fluid.storage)
