"""The strip-footing study: how far each method pushes a rigid footing into undrained
clay, against Prandtl's limit pressure ``(2 + pi) s_u``, under node refinement.

The built-in ``strip-footing`` case (footing width B = 1 m, symmetry half, weightless
normally consolidated Cam-clay, k = 0) is run by each method on grids of n x n nodes to
a settlement of 0.5 B, and once on a domain twice as wide and deep at the middle grid's
spacing (fem-th) to show the boundaries do not matter. ``s_u`` is the clay's plane-strain
undrained strength (:func:`soil.analytical.undrained_strength`).
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from comparisons.verification import _results  # noqa: E402
from soil.analytical import PRANDTL, undrained_strength  # noqa: E402
from soil.problems import load_case  # noqa: E402
from comparisons import tables  # noqa: E402

CASE = "strip-footing"
#: Methods of the study: the method and its overrides.
METHODS = {"efg": ("efg", ()), "fem-th": ("fem-th", ()),
           "fem-p1p1-stab": ("fem-p1p1-stab", ())}
#: Nodes per side of the 5 B x 5 B domain (spacing B/2, B/4, B/6).
GRIDS = (11, 21, 31)
#: A curve is "within" Prandtl's pressure from the first settlement where it is within
#: this fraction of it.
WITHIN = 0.05
#: Settlement [B] at which each curve's pressure is compared with Prandtl's.
AT = 0.1


def width(case):
    """Footing width B [m]: twice the segment (the case is the symmetry half)."""
    (_, footing), = case.boundary.segments()
    return 2 * (footing.end - footing.start)


def curves(methods=METHODS, grids=GRIDS, domain_grid=41):
    """Load-settlement curves of every method and grid, plus fem-th on the doubled
    domain (``domain_grid`` nodes a side: 41 has the spacing of the 21 x 21 grid).

    Returns
    -------
    pandas.DataFrame
        One row per time level: ``method, domain`` (side over B), ``nodes`` (n x n),
        ``settlement`` (over B), ``pressure`` (mean contact pressure over
        ``(2 + pi) s_u``), ``iterations``, ``substeps``, and per run ``run_time`` [s]
        and ``reached`` (the last converged settlement over B; a run that stops early
        is kept up to its last converged level).
    """
    case = load_case(CASE)
    B, s_u = width(case), undrained_strength(case.material())
    specs, labels = [], []
    for (label, (method, extra)), n in ((m, n) for m in methods.items() for n in grids):
        specs.append((CASE, (f"discretisation.nx={n}", f"discretisation.ny={n}", *extra),
                      method))
        labels.append((label, case.geometry.width / B, f"{n}x{n}"))
    big = (f"geometry.width={2 * case.geometry.width}",
           f"geometry.height={2 * case.geometry.height}",
           f"discretisation.nx={domain_grid}", f"discretisation.ny={domain_grid}")
    specs.append((CASE, big, "fem-th"))
    labels.append(("fem-th", 2 * case.geometry.width / B, f"{domain_grid}x{domain_grid}"))
    frames = []
    for (label, domain, nodes), result in zip(labels, _results(specs)):
        h, summary = result.history, result.summary
        frames.append(pd.DataFrame({
            "method": label, "domain": domain, "nodes": nodes,
            "settlement": h["settlement@footing"].to_numpy() / B,
            "pressure": h["pressure@footing"].to_numpy() / (PRANDTL * s_u),
            "iterations": h["iterations"].to_numpy(), "substeps": h["substeps"].to_numpy(),
            "run_time": summary["timings"]["total_s"],
            "reached": h["settlement@footing"].iloc[-1] / B}))
    return pd.concat(frames, ignore_index=True)


def summary(table, within=WITHIN, at=AT):
    """Per run: how far it got, where it comes within ``within`` of Prandtl's pressure,
    its pressure at ``at`` B and its cost.

    Returns
    -------
    pandas.DataFrame
        ``method, domain, nodes, reached`` (B), ``within_at`` (the first settlement
        over B where the pressure is within ``within`` of ``(2 + pi) s_u``; empty if
        never), ``at_0.1B`` (pressure over ``(2 + pi) s_u``), ``at_end``, ``run_time``
        [s], ``iterations_per_step``, ``cutbacks`` (levels that needed a smaller step).
    """
    rows = []
    for (method, domain, nodes), run in table.groupby(["method", "domain", "nodes"],
                                                      sort=False):
        s, p = run.settlement.to_numpy(), run.pressure.to_numpy()
        close = np.flatnonzero(np.abs(p - 1) <= within)
        rows.append({"method": method, "domain": domain, "nodes": nodes,
                     "reached": run.reached.iloc[0],
                     "within_at": s[close[0]] if close.size else "",
                     f"at_{at:g}B": float(np.interp(at, s, p)) if s[-1] >= at else "",
                     "at_end": p[-1], "run_time": run.run_time.iloc[0],
                     "iterations_per_step": run.iterations.sum() / len(run),
                     "cutbacks": int((run.substeps > 1).sum())})
    return pd.DataFrame(rows)


def figure(table, path):
    """Load-settlement curves over Prandtl's pressure, a panel per method, one line per
    grid (and the doubled domain, dashed)."""
    methods = list(dict.fromkeys(table.method))
    fig, axes = plt.subplots(1, len(methods), figsize=(4.6 * len(methods), 4.2),
                             sharey=True, constrained_layout=True, squeeze=False)
    for ax, method in zip(axes[0], methods):
        part = table[table.method == method]
        for k, ((domain, nodes), run) in enumerate(part.groupby(["domain", "nodes"],
                                                                sort=False)):
            big = domain > part.domain.min()
            ax.plot(run.settlement, run.pressure, "--" if big else "-", color=f"C{k}",
                    label=f"{nodes} nodes" + (f", domain {domain:g} B" if big else ""))
        ax.axhline(1.0, color="k", lw=1, label="Prandtl (2 + pi) s_u")
        ax.axhspan(1 - WITHIN, 1 + WITHIN, color="k", alpha=0.08)
        ax.set(title=method, xlabel="settlement / B")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0, 0].set_ylabel("mean contact pressure / (2 + pi) s_u")
    fig.suptitle("Rigid smooth strip footing on undrained Cam-clay (weightless, NC): "
                 f"band = within {WITHIN:.0%} of Prandtl", fontsize=10)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def section(table):
    """The report's strip-footing section from :func:`summary`'s table: figure, table
    and what they show."""
    at = f"at_{AT:g}B"
    base = table[table.domain == table.domain.min()]
    grids = base.pivot(index="method", columns="nodes", values=at)[
        list(dict.fromkeys(base.nodes))]
    fem = table[table.method == "fem-th"].assign(spacing=lambda t: t.domain / (
        t.nodes.str.split("x").str[0].astype(int) - 1))
    big = fem[fem.domain == fem.domain.max()].iloc[0]
    small = fem[(fem.domain == fem.domain.min())
                & np.isclose(fem.spacing, big.spacing)].iloc[0]
    stops = base[base.reached < base.reached.max()]
    return [
        "## Strip footing: how far each method gets (issue 15)",
        "",
        "![footing](figures/footing.png)",
        "",
        "A rigid smooth strip footing (B = 1 m, symmetry half) pushed at a constant rate "
        "into a weightless normally consolidated Cam-clay layer (Table 1, p'0 = 3 kPa, "
        "undrained, total stress zero at the start), 5 B wide and 5 B deep, to a "
        "settlement of 0.5 B in 100 steps (`soilwater run strip-footing --method "
        "METHOD`). Pressures are the mean contact pressure over Prandtl's (2 + pi) s_u, "
        "s_u = M p'_f / sqrt(3) with p'_f = p'0 exp(-Lambda), the clay's plane-strain "
        f"undrained strength ({undrained_strength(load_case(CASE).material()):.4g} kPa). "
        f"`within_at` is the first settlement (over B) within {WITHIN:.0%} of it; a run "
        "that fails stops at its last converged level (`time.on_failure = \"stop\"`): "
        "`reached`.",
        "",
        tables.to_markdown(table, floatfmt="{:.3g}"),
        f"At {AT:g} B the pressure over (2 + pi) s_u is, on "
        + ", ".join(grids.columns) + " nodes: "
        + "; ".join(f"{m} " + ", ".join(f"{v:.3g}" for v in row)
                    for m, row in grids.iterrows())
        + ". Beyond, no curve has a plateau: the pressure keeps rising as the footing "
        "sinks (the changing geometry, not captured by Prandtl's small-strain limit). "
        f"Doubling the domain (fem-th, {big.nodes} nodes on {big.domain:g} B, the "
        f"spacing of {small.nodes} on {small.domain:g} B) moves the pressure at {AT:g} B "
        f"by {100 * (big[at] / small[at] - 1):+.2g} % and at 0.5 B by "
        f"{100 * (big.at_end / small.at_end - 1):+.2g} %. "
        + ("Every run reaches 0.5 B." if stops.empty else "Runs that stop early: "
           + "; ".join(f"{r.method} on {r.nodes} nodes at {r.reached:.3g} B"
                       for r in stops.itertuples()) + "."),
        "",
    ]
