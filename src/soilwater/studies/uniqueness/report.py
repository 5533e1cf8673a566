"""The unconfined compression's loss of uniqueness: the continuum onset, the discrete
onsets and the ensemble of perturbed runs, and what of it is robust."""

from soilwater.studies.harness import tables
from soilwater.studies.harness.onset import continuum_onset
from soilwater.studies.harness.runs import DEPARTURE, ERR_NOISE
from soilwater.studies.harness.tables import below_noise, marked
from soilwater.studies.uniqueness import figures, study

NAME = "uniqueness"
#: Columns of the bifurcation table that depend on the branch round-off chose.
BRANCH_ENSEMBLE = ("departed", "departure_from", "departure_to", "err_after_min",
                   "err_after_max")


def run(root, inputs):
    """The tables ``continuum_onset``, ``bifurcation_ensemble`` and ``bifurcation`` and
    their two figures; returns them as ``{"continuum", "ensemble", "bifurcation"}``."""
    continuum = continuum_onset()
    ensemble = study.ensemble()
    summary = study.summary(ensemble, continuum)
    for table, stem in ((continuum, "continuum_onset"), (ensemble, "bifurcation_ensemble"),
                        (summary, "bifurcation")):
        tables.write(table, root / "tables" / stem)
    figures.uniqueness(ensemble, continuum, root / "figures" / "uniqueness.png")
    figures.bifurcation_ensemble(ensemble, summary,
                                 root / "figures" / "bifurcation_ensemble.png")
    return {"continuum": continuum, "ensemble": ensemble, "bifurcation": summary}


def section(data):
    """The section's markdown lines: onsets, ensemble, what is robust."""
    bif = data["bifurcation"].set_index("run")
    cont = data["continuum"]
    c_onset = bif.continuum_onset.iloc[0]
    at = cont.iloc[(cont.strain - c_onset).abs().argmin()]
    lost = bif[bif.onset.notna()]
    kept = bif[bif.onset.isna()]
    plain = bif.loc[["EFG, squares, plain Gauss", "EFG, Delaunay, plain Gauss"], "err_before"]
    consistent = bif.err_before.drop(plain.index)
    steady = kept.drop(plain.index, errors="ignore")
    steady = steady[steady.departed == 0]
    return [
        "### Loss of uniqueness of the undrained solution",
        "",
        "![uniqueness](figures/uniqueness.png)",
        "",
        "The homogeneous state solves the undrained problem at every strain, but not always "
        "uniquely. Each unconfined-compression run records per step the smallest "
        "eigenvalue of the displacement block of its tangent on the undrained constraint "
        "(Hill's sufficient condition, against the H1 norm, over the initial P-wave "
        "modulus: `diagnostics.uniqueness`). Beside it, the continuum criterion of "
        "Rudnicki and Rice along the driver's path (the acoustic tensor of the undrained "
        "tangent, isochoric band modes) is lost at "
        f"{c_onset * 100:.2f} % axial strain (eta/M = {at.eta_over_M:.4f}), for bands "
        f"whose normal is inclined {at.band_angle:.1f} degrees to the horizontal. "
        "Discrete onsets: "
        + (", ".join(f"{run} {r.onset * 100:.2f} %" for run, r in lost.iterrows())
           or "none")
        + "; the indicator stays positive throughout for "
        + (", ".join(kept.index) or "no run") + ".",
        "",
        "![ensemble](figures/bifurcation_ensemble.png)",
        "",
        "Ensemble: each run on the built-in nodes and with its interior nodes jittered "
        "by " + ", ".join(f"{j:g}" for j in sorted(set(data["ensemble"].jitter)) if j)
        + " of the spacing and with the linear solvers "
        + ", ".join(sorted(set(data["ensemble"].solver)))
        + f" ({int(bif.members.iloc[0])} members per run). ERR before the onset is "
        "comparable between methods and the same on every member; past it, "
        "the members' spread (†) is the answer, not any one member:",
        "",
        tables.to_markdown(marked(below_noise(data["bifurcation"]), BRANCH_ENSEMBLE)
                           .drop(columns="continuum_onset"), floatfmt="{:.3g}"),
        "A member departs once its ERR exceeds "
        f"{DEPARTURE:g}. Robust: before the onset "
        + ("every run's ERR is below the Newton noise "
           f"({ERR_NOISE:g})" if consistent.max() < ERR_NOISE
           else "the largest ERR is " + ", ".join(f"{r} {v:.2g}"
                                                  for r, v in consistent.items()))
        + " except with the paper's plain Gauss quadrature ("
        + ", ".join(f"{run} {v:.2g}" for run, v in plain.items())
        + "), whose error is quadrature, not round-off"
        + ("; no member of " + ", ".join(steady.index)
           + " (consistent quadrature, indicator positive throughout) departs at all"
           if len(steady) else "")
        + ". Which members of the other runs depart, where and how far is "
        "branch-dependent (†).",
    ]
