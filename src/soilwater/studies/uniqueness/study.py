"""The undrained bifurcation of the unconfined compression, measured (report section).

Past the loss of uniqueness of the homogeneous undrained solution
(:mod:`soilwater.diagnostics.bifurcation`) round-off chooses the branch, so a single run's
ERR says nothing about a method. Here:

* :func:`soilwater.studies.harness.onset.continuum_onset`: the Rudnicki-Rice criterion
  along the stress-point driver's path, the material's own onset;
* :func:`ensemble`: every run of :data:`soilwater.studies.harness.runs.PATH_RUNS` with its node
  set jittered (:data:`JITTERS`, a fraction of the spacing) and with each linear solver,
  the unperturbed members recording the discrete indicator per step;
* :func:`summary`: per run, the discrete onset, ERR before it (comparable between methods)
  and the spread of the ensemble after it (branch-dependent).
"""

import numpy as np
import pandas as pd

from soilwater.studies.harness import runner
from soilwater.studies.harness.onset import solvers
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.runs import DEPARTURE, PATH_RUNS, UNIQUENESS
from soilwater.diagnostics.bifurcation import onset
from soilwater.errors import SoilwaterError

CASE = "unconfined-compression"
#: Node jitters of the ensemble, as fractions of the nodal spacing (0: the built-in nodes).
JITTERS = pick((0.0, 1e-12, 1e-9, 1e-6), (0.0,))


def ensemble(runs=PATH_RUNS, jitters=JITTERS, linear_solvers=None):
    """ERR per step of every member: each run x jitter x linear solver.

    Returns
    -------
    pandas.DataFrame
        Long format: ``run, jitter, solver, step, strain, err`` and ``uniqueness`` (the
        discrete indicator; NaN for jittered members, which do not compute it).
    """
    members = [(label, method, overrides, jitter, solver)
               for label, (method, overrides) in runs.items() for jitter in jitters
               for solver in (linear_solvers or solvers())]
    jobs = [runner.Job(CASE, method, overrides + _perturbation(jitter), (),
                       linear_solver=solver)
            for _, method, overrides, jitter, solver in members]
    outcomes = runner.run(jobs)
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SoilwaterError(f"{len(failed)} ensemble run(s) failed, first: "
                             f"{failed[0].job.method} {' '.join(failed[0].job.overrides)}: "
                             f"{failed[0].error}")
    frames = []
    for (label, _, _, jitter, solver), outcome in zip(members, outcomes):
        h = outcome.result.history
        frames.append(pd.DataFrame({
            "run": label, "jitter": jitter, "solver": solver, "step": h.index + 1,
            "strain": h.eps_a, "err": h.err.astype(float),
            "uniqueness": h.uniqueness if "uniqueness" in h else np.nan}))
    return pd.concat(frames, ignore_index=True)


def _perturbation(jitter):
    """Overrides of a member: on the built-in nodes those of the report's own runs
    (:data:`soilwater.studies.harness.runs.UNIQUENESS`, so they share the cache), else jittered
    nodes."""
    if jitter == 0:
        return UNIQUENESS[CASE]
    return (f"discretisation.jitter={jitter!r}",)


def summary(members, continuum):
    """Per run: onsets, ERR before the discrete onset and the ensemble after it.

    Returns
    -------
    pandas.DataFrame
        ``run``; ``onset`` (discrete, strain where the indicator of the unperturbed SuperLU
        member first reaches zero, NaN if never) and ``continuum_onset``; ``members``;
        ``err_before`` (largest ERR of any member before the onset, or over the whole run
        without one); after the onset, branch-dependent: ``departed`` (members whose ERR
        exceeds :data:`DEPARTURE`), ``departure_from``/``departure_to``
        (the range of strains where they do), ``err_after_min``/``err_after_max`` (the
        range over members of their largest ERR after the onset).
    """
    rows = []
    c_onset = onset(continuum.strain, continuum.indicator)
    for run, group in members.groupby("run", sort=False):
        base = group[(group.jitter == 0) & (group.solver == group.solver.iloc[0])]
        start = onset(base.strain, base.uniqueness)
        before = group.strain < start if np.isfinite(start) else np.ones(len(group), bool)
        err_before = group.err[before].max()
        after = group[~before]
        peak = after.groupby(["jitter", "solver"]).err.max()
        late = after[after.err > DEPARTURE]
        first = late.groupby(["jitter", "solver"]).strain.min()
        rows.append({"run": run, "onset": start, "continuum_onset": c_onset,
                     "members": group.groupby(["jitter", "solver"]).ngroups,
                     "err_before": err_before, "departed": len(first),
                     "departure_from": first.min() if len(first) else np.nan,
                     "departure_to": first.max() if len(first) else np.nan,
                     "err_after_min": peak.min() if len(peak) else np.nan,
                     "err_after_max": peak.max() if len(peak) else np.nan})
    return pd.DataFrame(rows)
