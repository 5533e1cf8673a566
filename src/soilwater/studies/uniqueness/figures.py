"""Figures of the uniqueness section: the indicators against strain and the ensemble's
spread; each saves a PNG and returns its path."""

import matplotlib.pyplot as plt
import numpy as np

from soilwater.studies.harness import figures
from soilwater.studies.harness.runs import run_style


def uniqueness(members, continuum, path):
    """The discrete uniqueness indicator of every run against strain, with the continuum
    (Rudnicki-Rice) indicator along the driver's path; symmetric-log axis (both cross
    zero by a few 1e-4 of the modulus)."""
    fig, ax = plt.subplots(figsize=(7.2, 4.8), constrained_layout=True)
    ax.plot(continuum.strain * 100, continuum.indicator, "k-", lw=4, alpha=0.3,
            label="continuum (acoustic tensor), driver path")
    base = members[members.jitter == 0]
    for k, (run, group) in enumerate(base.groupby("run", sort=False)):
        first = group[group.solver == group.solver.iloc[0]]
        ax.plot(first.strain * 100, first.uniqueness, lw=1.3, label=run, **run_style(k))
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_yscale("symlog", linthresh=1e-4)
    ax.set(xlabel="axial strain (%)", ylabel="smallest eigenvalue / P-wave modulus",
           title="Unconfined compression: uniqueness of the undrained solution\n"
           "(discrete: tangent on the undrained constraint; below zero uniqueness is not "
           "guaranteed)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return figures.save(fig, path)


def bifurcation_ensemble(members, summary, path):
    """ERR of every ensemble member (jittered nodes, both linear solvers) per run: the
    band between the smallest and the largest member, the members as thin lines, the
    discrete and continuum onsets as vertical lines."""
    runs = list(dict.fromkeys(members.run))
    fig, axes = plt.subplots(2, -(-len(runs) // 2), figsize=(12, 6.8), sharex=True,
                             sharey=True, constrained_layout=True, squeeze=False)
    onsets = summary.set_index("run")
    for ax, run in zip(axes.T.flat, runs):
        part = members[members.run == run]
        band = part.groupby("step").agg(strain=("strain", "mean"), low=("err", "min"),
                                        high=("err", "max"))
        ax.fill_between(band.strain * 100, band.low.clip(lower=1e-9),
                        band.high.clip(lower=1e-9), color="C0", alpha=0.25,
                        label="ensemble band")
        for (jitter, solver), m in part.groupby(["jitter", "solver"]):
            ax.plot(m.strain * 100, m.err.clip(lower=1e-9), lw=0.7,
                    color="C1" if solver == "pardiso" else "C0",
                    ls={0.0: "-", 1e-12: "--", 1e-9: "-.", 1e-6: ":"}.get(jitter, "-"))
        row = onsets.loc[run]
        if np.isfinite(row.onset):
            ax.axvline(row.onset * 100, color="C3", lw=1, label="discrete onset")
        ax.axvline(row.continuum_onset * 100, color="k", lw=1, ls=":",
                   label="continuum onset")
        ax.set_yscale("log")
        ax.set(title=run, ylim=(1e-9, 10))
        ax.grid(alpha=0.3, which="both")
    for ax in axes.flat[len(runs):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("axial strain (%)")
    for ax in axes[:, 0]:
        ax.set_ylabel("ERR (paper eq. 1), floor 1e-9")
    labels = {}
    for ax in axes.flat:
        labels.update(zip(*reversed(ax.get_legend_handles_labels())))
    fig.legend(list(labels.values()), list(labels), loc="outside lower center", fontsize=8,
               ncols=3)
    fig.suptitle("Unconfined compression: ERR of every ensemble member (blue SuperLU, "
                 "orange PARDISO; line style: node jitter 0, 1e-12, 1e-9, 1e-6 of the "
                 "spacing)", fontsize=10)
    return figures.save(fig, path)
