"""Figures of the unconfined compression and simple shear (paper Figs. 4 and 6), drawn
from :func:`soilwater.studies.verification.study.stress_paths`: the stress paths against
the stress-point driver (:func:`stress_paths`), their distance from it
(:func:`path_errors`) and the ERR of the nodal stretching (:func:`err_history`). Each is
one slide (:mod:`soilwater.studies.harness.figures`); stresses are over the initial
mean effective stress p'0, strains in %.
"""

import numpy as np
from matplotlib.lines import Line2D

from soilwater.studies.harness import figures
from soilwater.studies.harness.runs import ERR_NOISE

#: One marker per run, in the order of the table.
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")
#: The stress-path frame: p'/p'0 and q/p'0 shown [-].
FRAME = ((0.45, 1.05), (0.0, 0.85))
#: ERR values below this are drawn on it, marked [-].
ERR_FLOOR = 1e-12
STRAIN = {"unconfined-compression": "axial strain [%]", "simple-shear": "shear strain [%]"}


def _runs(part):
    """``(k, run label, its rows)`` of one case's table, in table order."""
    return [(k, run, group) for k, (run, group) in enumerate(part.groupby("run",
                                                                           sort=False))]


def _stopped(group, part):
    """Whether a run ends before the case's other runs (it failed to converge)."""
    return group.time.iloc[-1] < part.time.max() * (1 - 1e-9)


def _marks(x, y, k, count, per_run=4):
    """Indices of ``per_run`` markers of the k-th of ``count`` runs along the curve
    (x, y): equally spaced in its arc length (in axes-fraction units of the frame),
    shifted by k / count of a spacing, so that runs on one curve show their markers at
    different places."""
    (x0, x1), (y0, y1) = FRAME
    length = np.r_[0.0, np.cumsum(np.hypot(np.diff(x) / (x1 - x0), np.diff(y) / (y1 - y0)))]
    targets = (np.arange(per_run) + (k + 0.5) / count) / per_run * length[-1]
    return sorted(set(np.searchsorted(length, targets).clip(0, len(x) - 1).tolist()))


def _run_handles(runs):
    """Legend handles of the runs: each its colour, line and marker."""
    return [Line2D([], [], color=f"C{k}", marker=MARKERS[k % len(MARKERS)], lw=1.5,
                   label=run) for k, run, _ in runs]


def stress_paths(table, path, frame=FRAME):
    """``path``: q/p'0 against p'/p'0 of every run and the stress-point driver, a panel
    per case (shared axes). The driver is a thick black line beneath the runs; each run
    carries its own marker, placed at different points along the path for each run so
    that runs lying on the driver stay tellable apart. A path that leaves ``frame`` is
    marked where it leaves, with the strain there and its farthest p'/p'0, and a run that
    stops before the others is marked at its end.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.verification.study.stress_paths`.
    path : str or Path
    frame : ((float, float), (float, float))
        Limits of p'/p'0 and q/p'0 shown [-].

    Returns
    -------
    pathlib.Path
    """
    cases = list(dict.fromkeys(table.case))
    (x0, x1), (y0, y1) = frame
    notes = set()
    with figures.style():
        fig, axes = figures.slide(1, len(cases), sharex=True, sharey=True, squeeze=False)
        for ax, case in zip(axes[0], cases):
            part = table[table.case == case]
            runs = _runs(part)
            first = runs[0][2]
            ax.plot(np.r_[1.0, first.p_driver], np.r_[0.0, first.q_driver], color="black",
                    lw=7, alpha=0.35, zorder=1, solid_capstyle="butt")
            for k, run, group in runs:
                p, q = np.r_[1.0, group.p], np.r_[0.0, group.q]
                outside = np.flatnonzero((p < x0) | (p > x1) | (q < y0) | (q > y1))
                inside = outside[0] if outside.size else len(p)
                ax.plot(p, q, color=f"C{k}", lw=1.5, marker=MARKERS[k % len(MARKERS)],
                        ms=9, mec="black", mew=0.6,
                        markevery=_marks(p[:inside], q[:inside], k, len(runs)))
                if outside.size:
                    edge = (np.clip(p[inside], x0, x1), np.clip(q[inside], y0, y1))
                    ax.plot(*edge, ">", color=f"C{k}", mec="black", ms=12, zorder=7,
                            clip_on=False)
                    ax.annotate(f"{run}: leaves the frame at "
                                f"{100 * group.strain.iloc[inside - 1]:.2g} % strain,\n"
                                f"reaches p'/p'$_0$ = {p.max():.3g}", edge,
                                xytext=(-14, -44), textcoords="offset points", ha="right",
                                fontsize=11, arrowprops={"arrowstyle": "-", "color": "0.4"})
                    notes.add("leaves")
                if _stopped(group, part):
                    ax.plot(p[-1], q[-1], mfc=f"C{k}", **figures.STOPPED)
                    notes.add("stopped")
            ax.set_title(case.replace("-", " "))
            ax.set_xlabel("mean effective stress p'/p'$_0$ [-]")
        axes[0, 0].set(xlim=frame[0], ylim=frame[1],
                       ylabel="deviator stress q/p'$_0$ [-]")
        handles = [Line2D([], [], color="black", lw=7, alpha=0.35,
                          label="stress-point driver (closed form)"),
                   *_run_handles(runs)]
        if "leaves" in notes:
            handles.append(Line2D([], [], marker=">", ls="none", color="0.6", mec="black",
                                  ms=14, label="path leaves the frame (annotated)"))
        if "stopped" in notes:
            handles.append(Line2D([], [], mfc="white", label="run stops early",
                                  **figures.STOPPED))
        fig.legend(handles=handles, loc="outside lower center", ncol=4)
        fig.suptitle("Stress paths of the homogeneous tests (paper Fig. 4): each run "
                     "against the stress-point driver (nodal or domain averages)")
        return figures.save(fig, path)


def path_errors(table, path):
    """``path``: each run's distance from the driver's path, ``max(|p' - p'_driver|,
    |q - q_driver|) / p'0``, against the strain, log scale, a panel per case (shared
    distance axis); a run that stops before the others is marked at its end.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.verification.study.stress_paths`.
    path : str or Path

    Returns
    -------
    pathlib.Path
    """
    cases = list(dict.fromkeys(table.case))
    stopped = False
    with figures.style():
        fig, axes = figures.slide(1, len(cases), sharey=True, squeeze=False)
        for ax, case in zip(axes[0], cases):
            part = table[table.case == case]
            for k, run, group in _runs(part):
                gap = np.maximum(np.abs(group.p - group.p_driver),
                                 np.abs(group.q - group.q_driver))
                every = max(len(gap) // 5, 1)
                ax.semilogy(100 * group.strain, gap, color=f"C{k}", lw=1.5,
                            marker=MARKERS[k % len(MARKERS)], ms=7, mec="black", mew=0.5,
                            markevery=(k * every // len(part.run.unique()), every))
                if _stopped(group, part):
                    ax.plot(100 * group.strain.iloc[-1], gap.iloc[-1], mfc=f"C{k}",
                            **figures.STOPPED)
                    stopped = True
            ax.set(title=case.replace("-", " "), xlabel=STRAIN.get(case, "strain [%]"))
            ax.grid(which="both")
        axes[0, 0].set_ylabel("distance from the driver's path / p'$_0$ [-]")
        handles = _run_handles(_runs(table[table.case == cases[-1]]))
        if stopped:
            handles.append(Line2D([], [], mfc="white", label="run stops early",
                                  **figures.STOPPED))
        fig.legend(handles=handles, loc="outside lower center", ncol=4)
        fig.suptitle("How far each run's stress path lies from the driver's "
                     "(largest of the p' and q differences)")
        return figures.save(fig, path)


def err_history(table, path, case="unconfined-compression", floor=ERR_FLOOR):
    """``path``: paper Fig. 6, ERR (eq. 1) against the axial strain for every run of
    ``case``, log scale, with the noise level of the Newton tolerance
    (:data:`~soilwater.studies.harness.runs.ERR_NOISE`, below which the digits depend on
    the linear solver); values below ``floor`` are drawn on it and marked.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`soilwater.studies.verification.study.stress_paths`.
    path : str or Path
    case : str
    floor : float
        Smallest ERR shown [-].

    Returns
    -------
    pathlib.Path
    """
    part = table[table.case == case]
    runs = _runs(part)
    clipped = False
    with figures.style():
        fig, ax = figures.slide()
        for k, run, group in runs:
            strain = 100 * group.strain
            every = max(len(group) // 5, 1)
            ax.semilogy(strain, group.err.clip(lower=floor), color=f"C{k}", lw=1.5,
                        marker=MARKERS[k % len(MARKERS)], ms=7, mec="black", mew=0.5,
                        markevery=(k * every // len(runs), every))
            low = group.err < floor
            if low.any():
                ax.plot(strain[low], np.full(low.sum(), floor), "v", color=f"C{k}",
                        mec="black", **figures.CLIPPED)
                clipped = True
        ax.axhline(ERR_NOISE, color="black", ls=":", lw=1.5)
        handles = _run_handles(runs)
        handles.append(Line2D([], [], color="black", ls=":", lw=1.5,
                              label=f"noise of the Newton tolerance ({ERR_NOISE:g})"))
        if clipped:
            handles.append(Line2D([], [], marker="v", color="0.6", mec="black",
                                  label=f"below {floor:g} (drawn on it)", **figures.CLIPPED))
        ax.set(xlabel=STRAIN.get(case, "strain [%]"), ylabel="ERR (paper eq. 1) [-]",
               title=f"{case.replace('-', ' ')}: error of the nodal stretching D$_{{22}}$ "
                     "(paper Fig. 6)")
        ax.grid(which="both")
        fig.legend(handles=handles, loc="outside right upper")
        return figures.save(fig, path)
