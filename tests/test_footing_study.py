"""The strip-footing study's tables and verdict (:mod:`soilwater.studies.footing.study`,
:mod:`soilwater.studies.footing.domain`, :mod:`soilwater.studies.harness.grids`) on curves made by
hand, where every number is known; the runs themselves are `make report`'s."""

import numpy as np
import pandas as pd
import pytest

from soilwater.studies.footing import study as footing
from soilwater.studies.footing import domain as footing_domain
from soilwater.studies.harness.grids import growing, refined
from soilwater.references.closed_forms import PRANDTL, undrained_strength
from soilwater.case.loader import load_case

S = np.linspace(0.005, 0.5, 100)


def _run(label, core, pressure, reached=0.5, distortion=None, steps=100, method=None):
    keep = S <= reached + 1e-12
    return pd.DataFrame({
        "label": label, "method": method or label.split(",")[0], "core": core,
        "nodes": f"{5 * core + 1}x{5 * core + 1}", "steps": steps, "to": S[-1],
        "settlement": S[keep], "pressure": pressure[keep], "min_angle": 14.0,
        "min_quality": 0.4, "distortion": (np.ones(len(S)) if distortion is None
                                           else distortion)[keep],
        "min_rcond": np.nan, "iterations": 5, "substeps": 1, "run_time": 10.0 * core,
        "reached": S[keep][-1]})


REF = 1.2 * S / (0.11 + S)  # 0.95 of Prandtl's at S = 0.418


def test_summary_measures_against_the_reference():
    """A run 10 % above the reference has the error 0.1; one that stops at 0.3 B has no
    pressure at 0.5 B; distortion passing a third is dated; Prandtl's band is entered
    where the curve crosses 0.95."""
    table = pd.concat([
        _run("fem-th", 12, REF),
        _run("efg", 12, 1.1 * REF, distortion=1 - 2 * S),
        _run("fem-p1p1-stab", 12, REF, reached=0.3)], ignore_index=True)
    summary = footing.summary(table, reference=("fem-th", 12)).set_index("label")
    assert summary.loc["fem-th", "error"] == 0
    assert summary.loc["efg", "error"] == pytest.approx(0.1, rel=1e-9)
    assert np.isnan(summary.loc["fem-p1p1-stab", "at_0.5B"])
    assert summary.loc["fem-p1p1-stab", "reached"] == pytest.approx(0.3, abs=0.005)
    first = S[np.flatnonzero(1 - 2 * S < 1 / 3)[0]]
    assert summary.loc["efg", "distorted_at"] == first
    assert np.isnan(summary.loc["fem-th", "distorted_at"])
    assert summary.loc["fem-th", "within_at"] == pytest.approx(0.42)
    assert summary.loc["fem-th", "at_0.1B"] == pytest.approx(1.2 * 0.1 / 0.21, rel=1e-3)


def _deep(label, factor, reached):
    """A run to 1 B on the built-in nodes (core 8) whose curve is the reference's times
    ``factor``, stopping at ``reached``."""
    deep = np.linspace(0.005, 1.0, 200)
    keep = deep <= reached + 1e-12
    return pd.DataFrame({
        "label": f"{label}, to 1 B", "method": label.split("+")[0], "core": 8,
        "nodes": "41x41", "steps": 100, "to": 1.0, "settlement": deep[keep],
        "pressure": factor * 1.2 * deep[keep] / (0.11 + deep[keep]), "min_angle": 14.0,
        "min_quality": 0.4, "distortion": 1.0, "min_rcond": np.nan, "iterations": 5,
        "substeps": 1, "run_time": 100.0, "reached": deep[keep][-1]})


def _study(efg_factor, fem_deep_reach, paper=None):
    """Curves of the study; ``paper``: ``(factor, reached)`` of the EFG variant
    ``efg-paper`` on every density and to 1 B, or None for none."""
    runs = []
    for core in (4, 8, 12):
        runs += [_run("fem-th", core, REF * (1 + 0.01 * (12 - core))),
                 _run("fem-p1p1-stab", core, REF * 1.05),
                 _run("efg", core, REF * efg_factor)]
        if paper:
            runs.append(_run("efg-paper", core, REF * paper[0],
                             reached=min(paper[1], 0.5)))
    runs.append(_run("efg-paper, 400 steps", 4, REF * efg_factor, steps=400))
    runs += [_deep("efg", efg_factor, 1.0), _deep("fem-th", 1.0, fem_deep_reach),
             _deep("fem-p1p1-stab", 1.05, fem_deep_reach)]
    if paper:
        runs.append(_deep("efg-paper", paper[0], paper[1]))
    table = pd.concat(runs, ignore_index=True)
    return footing.summary(table, reference=("fem-th", 12)), table


@pytest.mark.parametrize("efg_factor, fem_deep_reach, paper, expected", [
    (1.3, 1.0, None, "refuted"),        # FEM reaches as far, Taylor-Hood nearer everywhere
    (1.0, 1.0, None, "open"),           # as far and as near: nothing settles it
    (1.0, 0.6, None, "supported"),      # EFG goes further on the built-in nodes, as near
    (1.3, 1.0, (1.3, 0.4), "refuted"),  # a variant that stops early and is no nearer
    (1.3, 1.0, (1.0, 0.4), "open"),     # a variant as near as Taylor-Hood, but shorter
    (1.3, 0.6, (1.0, 1.0), "supported"),  # a variant further on the built-in nodes
])
def test_verdict_follows_the_measures(efg_factor, fem_deep_reach, paper, expected):
    assert footing.verdict(*_study(efg_factor, fem_deep_reach, paper))[0] == expected


def test_the_verdict_names_each_efg_variant():
    measured = footing.verdict(*_study(1.3, 1.0, (1.0, 0.4)))[1]
    assert "efg-paper 0.4" in measured and "for efg-paper (" in measured


def test_the_section_counts_only_the_paper_schemes_step_series():
    summary, _ = _study(1.3, 1.0, (1.0, 0.4))
    text = "\n".join(footing.section(summary))
    assert "efg-paper on the coarsest nodes with 100, 400 steps" in text
    assert "efg-paper on 21x21 nodes at 0.4 B" in text


def test_domain_summary_recovers_a_flamant_shift():
    """Two curves, the larger domain's shifted right by exactly Flamant's settlement:
    the measured shift is Flamant's, and nothing is left once shifted back."""
    case = load_case(footing.CASE)
    su = undrained_strength(case.material())
    p = 1.5 * S / (0.15 + S)                                    # over Prandtl's
    extra = footing_domain.shift(case, p * PRANDTL * su, 2.0)   # m, B = 1 m
    small = pd.DataFrame({"domain": 10, "nodes": "a", "settlement": S, "pressure": p,
                          "shifted": S + extra})
    big = pd.DataFrame({"domain": 20, "nodes": "b", "settlement": S + extra, "pressure": p,
                        "shifted": S + extra})
    table = pd.concat([small, big], ignore_index=True)
    summary = footing_domain.summary(table).set_index("domain")
    flamant = float(footing_domain.shift(case, PRANDTL * su, 2.0))
    assert summary.loc[20, "shift@1"] == pytest.approx(flamant, rel=1e-3)
    assert summary.loc[20, "flamant@1"] == pytest.approx(flamant, rel=1e-12)
    assert summary.loc[20, "shifted_change"] < 1e-3


def test_tangent_shear_is_the_elastic_modulus_where_the_clay_cannot_yield():
    clay = load_case(footing.CASE, ["material.model=elastic"]).material()
    assert footing_domain.tangent_shear(clay) == clay.moduli()[1]


def test_node_families_put_a_node_on_the_footing_edge_and_fill_the_domain():
    assert load_case(footing.CASE) == load_case(footing.CASE, refined(8))
    for overrides in (refined(4), refined(12), growing(5.0), growing(40.0)):
        case = load_case(footing.CASE, overrides)
        x, y = case.grid_lines()
        assert 0.5 in np.round(x, 12) and x[-1] == y[-1] == case.geometry.width
        hx = np.diff(x)
        assert np.all(hx[1:] / hx[:-1] < 1.2)  # no jump between neighbouring spacings
