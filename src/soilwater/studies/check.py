"""``soilwater check``: rerun a fast subset and compare it with ``reports/reference/``.

Each reference is a CSV table with a JSON sidecar stating the command that made it, the
linear solver and CPU it was made with, and the tolerance a regression allows: a number
passes when ``|got - ref| <= rtol |ref| + atol``; text columns must match exactly.
``soilwater check --update`` rewrites the references (commit them deliberately: they are
what CI regresses against).

A table with a ``regime`` column (the unconfined compression) is checked for round-off
(the sidecar's ``branch`` rules). Rows the *reference* marks ``after`` lie past the loss of
uniqueness of the homogeneous solution (:mod:`soilwater.diagnostics.bifurcation`), where
round-off of the CPU, the BLAS or the linear solver may choose another branch: there ERR
and the indicator only meet one-sided bounds (``after_onset``). The averaged p', q are
still compared until the run departs from the homogeneous solution in the reference or in
the new table (its ERR above ``departure``), and from then on only meet their bounds
(``after_departure``): a 1e-12 node jitter moves fem-th's q by 5e-3 once it has departed.
"""

import json
import platform
from pathlib import Path

import numpy as np
import pandas as pd

from soilwater.studies.stability import study as stability
from soilwater.studies.harness.machine import cpu
from soilwater.studies.harness.metrics import moose_errors, terzaghi_errors
from soilwater.studies.harness.moose import moose_terzaghi
from soilwater.studies.harness.paths import REFERENCE
from soilwater.studies.harness.runner import Job, run
from soilwater.studies.harness.runs import DEPARTURE
from soilwater.material.driver import run_test
from soilwater.linalg.backends import identity
from soilwater.material.presets import material_from_spec

COMMAND = "soilwater check --update"


def driver_paths():
    """Stress-point driver: Table 1, undrained plane strain, both models, 21 samples."""
    frames = []
    for model in ("original", "modified"):
        clay = material_from_spec({"preset": "table1", "model": model})
        table = run_test(clay, "undrained-plane-strain", 0.2, points=20)
        frames.append(table.assign(model=model))
    return pd.concat(frames, ignore_index=True)


def unconfined_err():
    """EFG in the paper's configuration (Delaunay, squares) and fem-th unconfined
    compression in 50 steps: ERR, the
    uniqueness indicator and p', q (over p'0) per step; ``regime`` is ``after`` from the
    first step whose indicator is not positive (the discrete onset)."""
    runs = [("efg-paper", "efg.cells=delaunay"), ("efg-paper", "efg.cells=squares"),
            ("fem-th", "")]
    outcomes = _run([Job("unconfined-compression", method, tuple(filter(None, (o,)))
                         + ("time.steps=50", "diagnostics.uniqueness=true"))
                     for method, o in runs])
    frames = []
    for (method, option), result in zip(runs, outcomes):
        h, p0 = result.history, result.case.material().p0
        after = np.arange(1, len(h) + 1) >= (result.summary["uniqueness_onset_step"]
                                             or np.inf)
        frames.append(pd.DataFrame({"run": f"{method} {option}".strip(), "step": h.index,
                                    "regime": np.where(after, "after", "before"),
                                    "eps_a": h.eps_a, "p": h.p / p0, "q": h.q / p0,
                                    "err": h.err.astype(float),
                                    "uniqueness": h.uniqueness}))
    return pd.concat(frames, ignore_index=True)


def column_stability():
    """EFG soil column in the paper's configuration (5 x 41 nodes, first step, k = 0 and
    1e-5): the Table 2 sweep of the paper's three weight pairs at scale factors 1.3 and
    2.0."""
    pairs = {k: v for k, v in stability.COMBINATIONS.items() if k != "E-B/E-B"}
    return stability.table2(scales=(1.3, 2.0), combinations=pairs, method="efg-paper")


def consolidation_errors():
    """Terzaghi: EFG in the paper's configuration (3 x 21 nodes) against the closed form,
    fem-q1q1 against MOOSE."""
    efg, q1q1 = _run([Job("terzaghi", "efg-paper", ("discretisation.nx=3",
                                                   "discretisation.ny=21")),
                      Job("terzaghi", "fem-q1q1")])
    rows = []
    for name, result in (("efg-paper", efg), ("fem-q1q1", q1q1)):
        errors = terzaghi_errors(result)
        rows += [(name, f"closed form {k}", v) for k, v in errors.pop("window_errors").items()]
        rows += [(name, k, v) for k, v in errors.items()]
    rows += [("fem-q1q1", f"moose {k}", v)
             for k, v in moose_errors(q1q1, moose_terzaghi()).items()]
    return pd.DataFrame(rows, columns=["method", "metric", "value"])


#: name -> (function, rtol, atol, branch); atol may be ``{column: atol, "*": default}``;
#: ``branch`` holds the rules past the onset (module docstring): ``[low, high]`` bounds
#: (None: unbounded) and the departure threshold. Before the onset the homogeneous
#: solution is unique and ERR is the noise of the Newton tolerance (about 1e-6 with every
#: solver), compared to 1e-5; past it ERR and the indicator depend on the branch round-off
#: chose (EFG squares with SuperLU: ERR 3e-4 on one machine, 1.3e-3 on another).
BRANCH = {"after_onset": {"err": [0.0, None], "uniqueness": [None, None]},
          "after_departure": {"p": [0.0, None], "q": [0.0, None]},
          "departure": ["err", DEPARTURE]}
TABLES = {
    "driver_paths": (driver_paths, 1e-6, 1e-9, None),
    "unconfined_err": (unconfined_err, 1e-4, {"err": 1e-5, "uniqueness": 1e-6, "*": 1e-7},
                       BRANCH),
    "column_stability": (column_stability, 1e-4, 1e-6, None),
    "consolidation_errors": (consolidation_errors, 1e-4, 1e-6, None),
}


def _run(jobs):
    outcomes = run(jobs, cache_dir=None, progress=False)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise RuntimeError(f"check run failed: {failed[0].job}: {failed[0].error}")
    return [o.result for o in outcomes]


def update(folder=REFERENCE, names=None):
    """Recompute every table (or those ``names``) and write it with its sidecar; returns
    the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in names or TABLES:
        function, rtol, atol, branch = TABLES[name]
        function().to_csv(folder / f"{name}.csv", index=False)
        tolerance = {"rtol": rtol, "atol": atol, "rule": "|got - ref| <= rtol |ref| + atol"}
        if branch:
            tolerance["branch"] = branch
        sidecar = {"made_by": f"soilwater.studies.check.{function.__name__}",
                   "what": " ".join(function.__doc__.split()), "command": COMMAND,
                   "linear_solver": identity(),
                   "machine": f"{platform.machine()}, {cpu()}",
                   "tolerance": tolerance}
        (folder / f"{name}.json").write_text(json.dumps(sidecar, indent=2) + "\n")
        written += [folder / f"{name}.csv", folder / f"{name}.json"]
    return written


def compare(reference, got, rtol, atol, branch=None):
    """Differences of two tables as readable lines (empty when they agree).

    With ``branch`` rules (module docstring), columns past the onset (the reference's
    ``regime``) or past a departure check their bounds instead; ``regime`` itself is not
    compared.
    """
    if list(reference.columns) != list(got.columns) or len(reference) != len(got):
        return [f"shape or columns differ: reference {reference.shape} "
                f"{list(reference.columns)}, got {got.shape} {list(got.columns)}"]
    bounds, rows = _branch_rows(reference, got, branch) if branch else ({}, {})
    lines = []
    for column in reference.columns:
        if branch and column == "regime":
            continue
        ref, new = reference[column], got[column]
        bounded = rows.get(column, np.zeros(len(reference), bool))
        if pd.api.types.is_numeric_dtype(ref) and pd.api.types.is_numeric_dtype(new):
            a, b = ref.to_numpy(float), new.to_numpy(float)
            tol = atol.get(column, atol["*"]) if isinstance(atol, dict) else atol
            bad = ~(np.isclose(b, a, rtol=rtol, atol=tol) | (np.isnan(a) & np.isnan(b)))
            lines += [f"row {i}, {column}: reference {a[i]:.10g}, got {b[i]:.10g} "
                      f"(allowed {rtol:g} relative + {tol:g})"
                      for i in np.flatnonzero(bad & ~bounded)]
            if bounded.any():
                lines += _bounds(column, b, bounded, *bounds[column])
        else:
            bad = ref.astype(str).to_numpy() != new.astype(str).to_numpy()
            lines += [f"row {i}, {column}: reference {ref.iloc[i]!r}, got {new.iloc[i]!r}"
                      for i in np.flatnonzero(bad)]
    return lines


def _branch_rows(reference, got, branch):
    """Bounds per column and the rows where they replace the comparison: past the
    reference's onset, and past the first departure of either table (per run)."""
    after = reference["regime"].to_numpy() == "after"
    column, threshold = branch["departure"]
    above = (reference[column].to_numpy(float) > threshold) | (
        got[column].to_numpy(float) > threshold)
    departed = pd.Series(above).groupby(reference["run"].to_numpy()).cummax().to_numpy()
    rows = {c: after for c in branch["after_onset"]}
    rows.update({c: departed for c in branch["after_departure"]})
    return {**branch["after_onset"], **branch["after_departure"]}, rows


def _bounds(column, values, rows, low, high):
    """Lines for the ``rows`` of ``values`` outside ``[low, high]`` (or not finite)."""
    low = -np.inf if low is None else low
    high = np.inf if high is None else high
    bad = rows & ~((values >= low) & (values <= high))
    return [f"row {i}, {column}: got {values[i]:.10g}, outside the bounds [{low:g}, "
            f"{high:g}] past the loss of uniqueness" for i in np.flatnonzero(bad)]


def check(folder=REFERENCE, names=None):
    """Rerun the tables and compare them with the references in ``folder``.

    Returns
    -------
    dict
        ``{name: [difference lines]}``; all lists empty when everything agrees.
    """
    folder = Path(folder)
    report = {}
    for name in names or TABLES:
        function = TABLES[name][0]
        sidecar = json.loads((folder / f"{name}.json").read_text())["tolerance"]
        reference = pd.read_csv(folder / f"{name}.csv")
        got = pd.read_csv(_roundtrip(function()))
        report[name] = compare(reference, got, sidecar["rtol"], sidecar["atol"],
                               sidecar.get("branch"))
    return report


def _roundtrip(frame):
    """The table as it would be read back from CSV (same dtypes as the reference)."""
    from io import StringIO

    buffer = StringIO()
    frame.to_csv(buffer, index=False)
    buffer.seek(0)
    return buffer
