"""The EFG configurations on the report's cases: where the state lives (``efg.integration``),
the essential conditions (``efg.essential``) and the pressure stabilisation
(``efg.stabilisation``), to choose the recommended configuration.

Quoted by ``docs/theory/efg.rst`` ("The recommended configuration"). Each case is run as
its study runs it, with the study's overrides and error measure (the study's functions),
once per configuration ``integration/essential/stabilisation`` of the product of
``--schemes``, ``--essential`` and ``--stabilisation`` (the expensive cases on the subset
of :data:`CASES`), one run at a time in this process through the cached runner, every run
with ``time.on_failure = "stop"`` (``reached``: the fraction of its end time it got to;
``run_time`` [s] and ``newton`` iterations as the run measured them):

* ``terzaghi`` (5 x 41 nodes) and ``mandel``: the closed forms
  (:func:`~soilwater.studies.harness.metrics.terzaghi_errors`,
  :func:`~soilwater.studies.harness.metrics.mandel_errors`);
* ``unconfined-compression``: the path error over p'0 and ERR before the discrete onset
  of the loss of uniqueness and over the whole run
  (:func:`soilwater.studies.verification.study.path_summary`);
* ``large-strain-column`` and ``self-weight-consolidation``: the settlement against
  Gibson's (:func:`soilwater.studies.large_strain.study.summary`);
* ``rough-compression``: the shear band on the 111 nodes
  (:func:`soilwater.studies.shearband.study.summary`);
* ``essential``: the essential-conditions study's coupled runs that no other case here
  makes (:data:`soilwater.studies.essential.study.COUPLED`): the undrained simple shear's
  path error and the footing's first 0.05 B against fem-th;
* ``strip-footing-consolidation``: settlement when loaded against the undrained footing
  at the same pressure, final settlement, t50
  (:func:`soilwater.studies.footing_consolidation.study.summary`);
* ``inf-sup``: the numerical inf-sup test (:mod:`soilwater.diagnostics.pairs`) with the
  forms built on each scheme's own integration points and shape functions
  (:func:`soilwater.diagnostics.pairs._efg`).

``python docs/experiments/schemes.py`` (about an hour on 2 cores);
``--cases terzaghi mandel`` for a few of them.
"""

import argparse
import itertools

import numpy as np
import pandas as pd

from soilwater.case.loader import load_case
from soilwater.diagnostics import pairs
from soilwater.diagnostics.infsup import inf_sup
from soilwater.errors import SoilwaterError
from soilwater.references import gibson
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.studies.essential import study as essential
from soilwater.studies.footing import study as footing
from soilwater.studies.footing_consolidation import study as drained
from soilwater.studies.harness.grids import refined
from soilwater.studies.harness.metrics import mandel_errors, path_error, terzaghi_errors
from soilwater.studies.harness.runs import UNIQUENESS, solved
from soilwater.studies.large_strain import study as large
from soilwater.studies.shearband import study as shearband
from soilwater.studies.verification import study as verification

SCHEMES = ("paper", "gauss", "nodal")
ESSENTIAL = ("penalty", "nitsche")
STABILISATION = ("none", "perturbation")
#: The overrides of the verification study's EFG stress paths on Delaunay cells
#: (:data:`soilwater.studies.harness.runs.PATH_RUNS`).
PATHS = ("efg.cells=delaunay",)
#: The built-in footing's nodes (spacings per B) and its undrained run to 0.1 B at the
#: footing study's step (0.005 B), to which the loaded footing's settlement is compared.
CORE = 8
UNDRAINED = ("time.end=10.0", "time.steps=20")


def overrides(config, study=(), extra=()):
    """A run's overrides: the study's, ``extra`` (``--set``), the configuration
    ``(integration, essential, stabilisation)`` and ``time.on_failure = "stop"``."""
    scheme, condition, stabilisation = config
    return (*study, *extra, f"efg.integration={scheme}", f"efg.essential={condition}",
            f"efg.stabilisation={stabilisation}", "time.on_failure=stop")


def label(config):
    return "/".join(config)


def run(name, config, study=(), extra=()):
    """One EFG run of a built-in case through the cached runner, in this process.

    Returns
    -------
    result : Result or None
        None where the run failed outright (its first step).
    row : dict
        ``case, integration, essential, stabilisation``, ``reached`` (the last time over
        the case's end), ``completed``, ``run_time`` [s], ``newton`` (iterations) and
        ``stopped`` (where and why a step failed after every halving; empty if none).
    """
    row = {"case": name, **dict(zip(("integration", "essential", "stabilisation"), config))}
    try:
        result, = solved([(name, overrides(config, study, extra))])
    except SoilwaterError as err:
        print(f"{name} {label(config)}: failed: {err}")
        return None, {**row, "reached": 0.0, "completed": False, "run_time": np.nan,
                      "newton": np.nan, "stopped": str(err)}
    reached = float(result.history.time.iloc[-1] / result.case.time.end)
    return result, {**row, "reached": reached, "completed": reached > 1 - 1e-9,
                    "run_time": result.summary["timings"]["total_s"],
                    "newton": result.summary["newton_iterations"],
                    "stopped": result.summary.get("stopped") or ""}


def consolidation(name, configs, extra=()):
    """Terzaghi or Mandel against the closed form (the consolidation study's runs)."""
    rows = []
    for config in configs:
        result, row = run(name, config, essential.COUPLED[name], extra)
        if result is None:
            rows.append(row)
        elif name == "terzaghi":
            errors = terzaghi_errors(result)
            rows.append({**row, **errors.pop("window_errors"), **errors})
        else:
            rows.append({**row, **mandel_errors(result)})
    return rows


def paths(configs, extra=()):
    """The unconfined compression's path error and ERR (the verification study's)."""
    name, rows = "unconfined-compression", []
    for config in configs:
        given = (*PATHS, *UNIQUENESS[name])
        result, row = run(name, config, given, extra)
        if result is not None:               # stress_paths reads the cached run
            table = verification.stress_paths(
                (name,), {label(config): ("efg", overrides(config, PATHS, extra))})
            summary = verification.path_summary(table).iloc[0]
            row.update(summary.drop(["case", "run"]).to_dict())
        rows.append(row)
    return rows


def gibson_settlement(configs, extra=()):
    """Both finite-strain columns against Gibson's (the large-strain study's summary)."""
    rows = []
    for name, config in itertools.product(large.CASES, configs):
        result, row = run(name, config, (), extra)
        if result is not None:
            reference, h = large.column(load_case(name)), result.history
            t, s = h.time.to_numpy(), h.settlement.to_numpy()
            g = gibson.solve(reference, t, *large.RESOLUTION).settlement
            table = pd.DataFrame({
                "case": name, "method": label(config), "time": t,
                "t_over_T": t / gibson.consolidation_time(reference), "settlement": s,
                "gibson": g, "error": s / g - 1, "iterations": h.iterations.to_numpy(),
                "run_time": row["run_time"]})
            row.update(large.summary(table).iloc[0].drop(
                ["case", "method", "run_time"]).to_dict())
        rows.append(row)
    return rows


def band(configs, extra=()):
    """The rough-platen shear band on the 111 nodes (the shear-band study's summary)."""
    predicted, rows = shearband.prediction(), []
    for config in configs:
        result, row = run(shearband.CASE, config, shearband.DENSITIES["coarse"], extra)
        if result is not None:
            table = shearband.curves([(label(config), "coarse", shearband.default(),
                                       result)])
            summary = shearband.summary(table, predicted).iloc[0]
            row.update(summary.drop(["method", "density", "run_time", "stopped"])
                       .rename({"reached": "strain_reached"}).to_dict())
        rows.append(row)
    return rows


def essential_runs(configs, extra=()):
    """The essential-conditions study's simple shear (path error) and footing (pressure
    against fem-th's over the first 0.05 B)."""
    rows = []
    for name, config in itertools.product(("simple-shear", "strip-footing"), configs):
        result, row = run(name, config, essential.COUPLED[name], extra)
        if result is not None and name == "simple-shear":
            row["path_error"] = path_error(result.history, result.case.material(),
                                           "undrained-simple-shear")
        elif result is not None:
            row["pressure_vs_fem_th"] = essential._against_taylor_hood(result.history)
        rows.append(row)
    return rows


def footing_consolidation(configs, extra=()):
    """The partially drained footing against the undrained one at the same pressure
    (the footing-consolidation study's summary; the undrained footing to 0.1 B)."""
    case = load_case(drained.CASE)
    B, s_u = footing.width(case), undrained_strength(case.material())
    (_, segment), = case.boundary.segments()
    q = segment.force / (segment.end - segment.start)
    (probe,) = case.probes
    rows = []
    for config in configs:
        result, row = run(drained.CASE, config, (), extra)
        if result is not None:
            h = result.history
            table = pd.DataFrame({
                "method": label(config), "time": h.time.to_numpy(),
                "settlement": h["settlement@footing"].to_numpy() / B,
                "pressure": h["pressure@footing"].to_numpy() / (PRANDTL * s_u),
                "excess": (h[f"p_w@{probe.name}"].to_numpy()
                           - case.initial_pore_pressure) / q,
                "iterations": h.iterations.to_numpy(), "run_time": row["run_time"]})
            undrained = footing.curves([(label(config), "efg", CORE, 100, overrides(
                config, (*refined(CORE), *UNDRAINED)))])
            row.update(drained.summary(table, undrained).iloc[0].drop(
                ["method", "run_time"]).to_dict())
        rows.append(row)
    return rows


def infsup(schemes, stabilisations, sizes):
    """beta and the zero modes per scheme, stabilisation, boundary and size, and whether
    beta levels off (:func:`soilwater.diagnostics.pairs.slopes`)."""
    rows = []
    for scheme, stabilisation, n in itertools.product(schemes, stabilisations, sizes):
        case = pairs.square(n, (f"efg.integration={scheme}",
                                f"efg.stabilisation={stabilisation}"))
        forms = pairs._efg(case)
        for boundary in pairs.BOUNDARIES:
            beta, zero = inf_sup(forms["S"], forms["B"], forms["T"], forms[boundary],
                                 hydrostatic=boundary == "dirichlet", C=forms["C"])
            rows.append({"method": f"efg {scheme}", "weights": forms["weights"],
                         "scale_u": forms["scale_u"], "scale_p": forms["scale_p"],
                         "boundary": boundary, "n": n, "h": 1.0 / (n - 1), "beta": beta,
                         "zero_modes": zero})
    table = pd.DataFrame(rows)
    stable = pairs.slopes(table) if len(sizes) > 1 else None
    if stable is not None:
        print(stable.to_string(index=False, float_format="{:.3g}".format))
    return [{"case": "inf-sup", **row} for row in table.to_dict("records")]


#: The cases: name -> (function of the configurations and ``--set`` overrides, the
#: essential conditions and stabilisations it runs by default, None: all given).
CASES = {
    "terzaghi": (lambda c, e: consolidation("terzaghi", c, e), None, None),
    "mandel": (lambda c, e: consolidation("mandel", c, e), None, None),
    "unconfined-compression": (paths, None, None),
    "large-strain": (gibson_settlement, None, ("none",)),
    "rough-compression": (band, None, None),
    "essential": (essential_runs, None, None),
    "strip-footing-consolidation": (footing_consolidation, ("penalty", "nitsche"),
                                    ("none",)),
}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=[*CASES, "inf-sup"],
                        choices=[*CASES, "inf-sup"])
    parser.add_argument("--schemes", nargs="+", default=list(SCHEMES), choices=SCHEMES)
    parser.add_argument("--essential", nargs="+", default=None, choices=ESSENTIAL,
                        help="default: each case's (all but where CASES says)")
    parser.add_argument("--stabilisation", nargs="+", default=None, choices=STABILISATION,
                        help="default: each case's (all but where CASES says)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(pairs.SIZES),
                        help="nodes per side of the inf-sup squares")
    parser.add_argument("--set", nargs="*", default=[],
                        help="more overrides of every run, key=value")
    args = parser.parse_args(argv)
    pd.set_option("display.width", 250)
    rows = []
    for name in args.cases:
        if name == "inf-sup":
            found = infsup(args.schemes, args.stabilisation or STABILISATION, args.sizes)
        else:
            function, conditions, stabilisations = CASES[name]
            configs = list(itertools.product(
                args.schemes, args.essential or conditions or ESSENTIAL,
                args.stabilisation or stabilisations or STABILISATION))
            found = function(configs, tuple(args.set))
        print(f"\n## {name}\n")
        print(pd.DataFrame(found).to_string(index=False, float_format="{:.4g}".format))
        rows += found
    return rows


if __name__ == "__main__":
    main()
