"""Run sets several studies share, and :func:`solved`, which runs them through the
cached runner.

The paper's Figs. 4 and 6 runs (:data:`PATH_RUNS`, drawn in :func:`run_style`) are
tabulated by the verification study and perturbed by the uniqueness study, whose ERR
thresholds (:data:`ERR_NOISE`, :data:`DEPARTURE`) the report's tables and verdicts
apply; :data:`FEM_METHODS` are the pairs of the column and consolidation studies.
"""

from soilwater.errors import SoilwaterError
from soilwater.studies.harness import runner
from soilwater.studies.harness.quick import pick


#: Overrides of every run of :data:`PATH_RUNS`: none, or half the cases' 100 steps in a
#: quick report.
PATH_STEPS = pick((), ("time.steps=50",))


#: The runs of the paper's Figs. 4 and 6: label -> (method, overrides): EFG in the
#: paper's configuration (``efg-paper``) with its cells and gradient corrections, EFG in
#: the recommended configuration (``efg``) and two FEM pairs; each with
#: :data:`PATH_STEPS`.
PATH_RUNS = {label: (method, (*overrides, *PATH_STEPS)) for label, (method, overrides) in {
    "EFG, Delaunay cells": ("efg-paper", ("efg.cells=delaunay",)),
    "EFG, square cells": ("efg-paper", ("efg.cells=squares",)),
    "EFG, Delaunay, plain Gauss": ("efg-paper", ("efg.cells=delaunay",
                                                 "efg.correction=none")),
    "EFG, squares, plain Gauss": ("efg-paper", ("efg.cells=squares", "efg.correction=none")),
    "EFG recommended": ("efg", ()),
    "FEM Taylor-Hood (fem-th)": ("fem-th", ()),
    "FEM P1/P1 (fem-p1p1)": ("fem-p1p1", ()),
}.items()}


#: Extra overrides per case of
#: :func:`soilwater.studies.verification.study.stress_paths`: the indicator where it is reported.
UNIQUENESS = {"unconfined-compression": ("diagnostics.uniqueness=true",)}


def solved(specs):
    """Results of ``(case, overrides[, method])`` runs (method default ``efg``) through
    the parallel, cached runner.

    Raises
    ------
    SoilwaterError
        If any run failed (a study's table needs them all), naming the first.
    """
    outcomes = runner.run([runner.Job(spec[0], spec[2] if len(spec) > 2 else "efg",
                                      tuple(spec[1])) for spec in specs])
    failed = [o for o in outcomes if not o.ok]
    if failed:
        raise SoilwaterError(f"{len(failed)} study run(s) failed, first: "
                             f"{failed[0].job.case} {' '.join(failed[0].job.overrides)}: "
                             f"{failed[0].error}")
    return [o.result for o in outcomes]


#: The scikit-fem reference methods.
FEM_METHODS = ("fem-th", "fem-p1p1", "fem-p1p1-stab", "fem-q1q1", "fem-q2q1")


def run_style(k):
    """Line style of the k-th run of :data:`PATH_RUNS` in a figure: colours for
    cells/methods, dashes for variants."""
    ls, color = [("-", "C0"), ("--", "C1"), (":", "C0"), (":", "C1"), ("-", "C4"),
                 ("-", "C2"), ("-.", "C3")][k % 7]
    return {"ls": ls, "color": color}


#: ERR of a homogeneous run below this is the noise of the Newton tolerance (measured
#: 3e-7 to 5e-6 with SuperLU and PARDISO on the 111-node specimen): its digits depend on
#: the linear solver and are reported only as "below".
ERR_NOISE = 1e-5


#: A member has departed from the homogeneous solution once its ERR exceeds this, a
#: hundred times the noise.
DEPARTURE = 100 * ERR_NOISE
