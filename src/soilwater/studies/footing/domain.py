"""How large the strip footing's domain must be: Taylor-Hood on square domains of
:data:`DOMAINS` B a side, equal spacings of B/8 at the footing growing by about 15 % per
cell beyond (:func:`soilwater.studies.harness.grids.growing`).

In plane strain there is no domain large enough for the settlement at a given load to
stop changing: a line load on an elastic body settles as the logarithm of the depth of
the base that holds it (Flamant, :func:`soilwater.references.closed_forms.flamant_settlement`). Each
doubling of a domain whose far field responds linearly moves the load-settlement curve
to the right by that amount and changes nothing else. A normally consolidated clay
yields at the first shear stress, so its far field is not elastic: it responds with the
undrained tangent shear modulus of its initial state (:func:`tangent_shear`), about
three quarters of the elastic G for Table 1, and Poisson's ratio 1/2 (undrained,
incompressible constituents). The study measures the shift between successive domains
against that prediction, and what is left once every curve is shifted to the largest
domain: the boundaries' effect on the mechanism under the footing.
"""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from soilwater.studies.harness import figures, tables
from soilwater.studies.footing.study import FROM
from soilwater.studies.harness.footing import CASE, time_steps, width
from soilwater.studies.harness.quick import pick
from soilwater.studies.harness.grids import growing, refined
from soilwater.studies.harness.runs import solved
from soilwater.references.closed_forms import (PRANDTL, flamant_settlement, undrained_poisson,
                             undrained_strength)
from soilwater.material.driver import run_test
from soilwater.case.loader import load_case

#: Sides of the square domains [B].
DOMAINS = pick((5, 10, 20, 40), (5, 10, 20))
#: Spacings per B at the footing (:func:`soilwater.studies.harness.grids.growing`).
CORE = pick(8, 4)
METHOD = "fem-th"
#: Pressures (over Prandtl's) at which the shift between successive domains is measured.
LEVELS = (0.5, 1.0)
#: Largest settlement [B] of the comparison of shifted curves (the largest domain's
#: curve, shifted least, must cover it).
UPTO = 0.45


def curves(domains=DOMAINS, method=METHOD):
    """Load-settlement curves of ``method`` on each domain.

    Returns
    -------
    pandas.DataFrame
        ``domain`` (side over B), ``nodes``, ``settlement`` (over B), ``pressure`` (over
        ``(2 + pi) s_u``) and ``shifted``: the settlement over B plus Flamant's extra
        settlement from this domain to the largest (:func:`shift`).
    """
    case = load_case(CASE)
    B = width(case)
    frames = []
    for domain, result in zip(domains, solved(
            [(CASE, (*growing(domain * B, CORE), f"time.steps={time_steps(case)}"), method)
             for domain in domains])):
        h, d = result.history, result.case.discretisation
        s, p = h["settlement@footing"].to_numpy() / B, h["pressure@footing"].to_numpy()
        frames.append(pd.DataFrame({
            "domain": domain, "nodes": f"{d.nx}x{d.ny}", "settlement": s,
            "pressure": p / (PRANDTL * undrained_strength(case.material())),
            "shifted": s + shift(case, p, max(domains) / domain) / B}))
    return pd.concat(frames, ignore_index=True)


def shift(case, pressure, ratio):
    """Flamant's extra settlement [m] of the footing at mean contact pressure
    ``pressure`` [kPa] when the domain grows ``ratio``-fold: the whole footing's force
    ``pressure x B`` on the clay's undrained tangent shear modulus (:func:`tangent_shear`)
    and undrained Poisson's ratio."""
    clay = case.material()
    return flamant_settlement(np.asarray(pressure) * width(case), tangent_shear(clay),
                              undrained_poisson(clay, case.fluid), ratio)


def tangent_shear(material, strain=1e-5):
    """Undrained tangent shear modulus at the initial state [kPa]: ``q / (3 eps_s)``
    after an undrained plane-strain compression of ``strain`` by the stress-point driver
    (``eps_s = 2 eps_a / sqrt(3)``); the shear modulus G where the material cannot
    yield.

    Examples
    --------
    Table 1's normally consolidated clay yields at once: 38.0 kPa against G = 51.6 kPa
    (``1 / (3 G_t) = 1 / (3 G) + MD kappa / (M^2 p'0 lambda)`` for the original model).

    >>> from soilwater.material.presets import material_from_spec
    >>> round(tangent_shear(material_from_spec({"preset": "table1"})), 1)
    38.0
    """
    if not material.plastic:
        return float(material.moduli()[1])
    path = run_test(material, "undrained-plane-strain", strain, points=1)
    return float(path.q.iloc[-1] / (2 * np.sqrt(3) * path.eps_a.iloc[-1]))


def summary(table, levels=LEVELS, upto=UPTO):
    """Per domain: pressures at 0.1 and 0.5 B, the shift of its curve from the next
    smaller domain (measured at the pressures ``levels`` over Prandtl's, and Flamant's),
    and the largest relative difference of its shifted curve from the next smaller
    domain's, from :data:`FROM` to ``upto`` B.

    Returns
    -------
    pandas.DataFrame
        ``domain, nodes, at_0.1B, at_0.5B``, per level ``shift@L`` and ``flamant@L``
        (settlement over B; NaN for the smallest domain) and ``shifted_change``.
    """
    case = load_case(CASE)
    su, B = undrained_strength(case.material()), width(case)
    rows, previous = [], None
    for domain, run in table.groupby("domain"):
        s, p, shifted = run.settlement.to_numpy(), run.pressure.to_numpy(), run.shifted
        row = {"domain": domain, "nodes": run.nodes.iloc[0],
               "at_0.1B": np.interp(0.1, s, p), "at_0.5B": np.interp(0.5, s, p)}
        for level in levels:
            measured = np.nan
            if previous is not None:
                measured = np.interp(level, p, s) - np.interp(level, previous.pressure,
                                                              previous.settlement)
            row[f"shift@{level:g}"] = measured
            row[f"flamant@{level:g}"] = (np.nan if previous is None else float(
                shift(case, level * PRANDTL * su, domain / previous.domain.iloc[0])) / B)
        row["shifted_change"] = np.nan
        if previous is not None:
            x = np.linspace(FROM, upto, 50)
            row["shifted_change"] = np.abs(np.interp(x, shifted, p) / np.interp(
                x, previous.shifted, previous.pressure) - 1).max()
        rows.append(row)
        previous = run
    return pd.DataFrame(rows)


def figure(table, path):
    """The curves of every domain as computed, and shifted by Flamant's settlement to
    the largest domain."""
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True, constrained_layout=True)
    for k, (domain, run) in enumerate(table.groupby("domain")):
        label = f"{domain:g} B ({run.nodes.iloc[0]} nodes)"
        axes[0].plot(run.settlement, run.pressure, color=f"C{k}", label=label)
        axes[1].plot(run.shifted, run.pressure, color=f"C{k}", label=label)
    axes[0].set(title=f"{METHOD} on square domains", xlabel="settlement / B [-]",
                ylabel="mean contact pressure / (2 + pi) s_u [-]")
    axes[1].set(title=f"shifted by Flamant's settlement to {max(table.domain):g} B",
                xlabel="(settlement + Flamant's extra settlement) / B [-]")
    for ax in axes:
        ax.axhline(1.0, color="k", lw=1, label="Prandtl (2 + pi) s_u")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return figures.save(fig, path)


def _enough(summary, limit=0.02):
    """The sentence on the smallest domain whose doubling moves the shifted curve by
    less than ``limit``, and on the built-in case's domain."""
    domains = summary.domain.to_numpy()
    change = summary.shifted_change.to_numpy()
    ok = np.flatnonzero(change[1:] < limit)
    built = load_case(CASE).geometry.width / width(load_case(CASE))
    own = np.flatnonzero(domains[:-1] == built)
    first = (f"Doubling moves the shifted curve by less than {100 * limit:g} % from "
             f"{domains[ok[0]]:g} B on" if ok.size else
             f"No doubling measured here moves the shifted curve by less than "
             f"{100 * limit:g} %")
    nodes = [len(load_case(CASE, refined(8, domain)).nodes()) for domain in (built,
                                                                             2 * built)]
    return first + (f"; the built-in case's {built:g} B moves it by "
                    f"{100 * change[own[0] + 1]:.2g} % (the price of EFG's cells, at most "
                    f"4 times longer than wide: {2 * built:g} B take {nodes[1] / nodes[0]:.1f}"
                    " times the nodes)." if own.size else ".")


def section(summary):
    """The report's lines on the domain study."""
    big = summary.iloc[-1]
    level = LEVELS[-1]
    return [
        "### How large the domain must be",
        "",
        "![footing domain](figures/footing_domain.png)",
        "",
        f"{METHOD} on square domains of " + ", ".join(f"{d:g}" for d in summary.domain)
        + " B (equal spacings of B/8 at the footing, growing about 15 % per cell "
        "beyond). Each doubling of the domain changes the pressure at 0.1 B by "
        + ", ".join(f"{100 * (b / a - 1):+.2g} %" for a, b in zip(
            summary["at_0.1B"], summary["at_0.1B"][1:]))
        + " and at 0.5 B by " + ", ".join(f"{100 * (b / a - 1):+.2g} %" for a, b in zip(
            summary["at_0.5B"], summary["at_0.5B"][1:]))
        + ": in plane strain no domain is large enough for that to stop, because a line "
        "load's settlement over an elastic base grows as ln(depth) (Flamant). At "
        + ("Prandtl's pressure" if level == 1 else f"{level:g} (2 + pi) s_u")
        + " each doubling moves the curve by "
        + ", ".join(f"{v:.3g}" for v in summary[f"shift@{level:g}"][1:])
        + f" B; Flamant's extra settlement of the footing's force on the far field (the "
        f"clay's undrained tangent shear modulus {tangent_shear(load_case(CASE).material()):.3g}"
        f" kPa, Poisson's ratio 1/2) is {big[f'flamant@{level:g}']:.3g} B per doubling. "
        "Shifted by it to the largest domain, successive curves differ by at most "
        + ", ".join(f"{100 * v:.2g} %" for v in summary.shifted_change[1:])
        + f" between {FROM:g} and {UPTO:g} B: what the boundaries still do to the "
        f"mechanism under the footing. {_enough(summary)} In the table, `shift@L` is the "
        "measured shift of the curve from the next smaller domain's at the pressure L "
        "(2 + pi) s_u and `flamant@L` Flamant's (both settlement over B), "
        "`shifted_change` the largest relative difference of the shifted curves.",
        "",
        tables.to_markdown(summary, floatfmt="{:.3g}"),
        "",
    ]
