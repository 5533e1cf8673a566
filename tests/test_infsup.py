"""The numerical inf-sup test: it must rate a known-stable pair stable and a known-unstable
one unstable before it rates EFG, and its EFG ``v = 0`` subspace must vanish on the
boundary."""

import numpy as np
import pandas as pd
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from soilwater.cli import main
from soilwater.diagnostics.pairs import RCOND, SAMPLES, measure, slopes, square
from soilwater.efg.boundary import boundary_points, segment_edges
from soilwater.efg.mls import ShapeFunctions
from soilwater.diagnostics.infsup import inf_sup

SIZES = (3, 5, 9, 17)


@pytest.fixture(scope="module")
def fem():
    table = measure(["fem-th", "fem-p1p1", "fem-q2q1"], SIZES)
    return table, slopes(table).set_index(["method", "boundary"])


@pytest.mark.parametrize("boundary", ["free", "dirichlet"])
def test_taylor_hood_and_q2q1_level_off_and_have_no_spurious_modes(fem, boundary):
    table, fits = fem
    for method in ("fem-th", "fem-q2q1"):
        assert fits.loc[(method, boundary), "stable"]
        rows = table[(table.method == method) & (table.boundary == boundary)]
        assert (rows.zero_modes == 0).all() and rows.beta.min() > 0.3


@pytest.mark.parametrize("boundary", ["free", "dirichlet"])
def test_p1p1_decays_and_has_spurious_modes(fem, boundary):
    table, fits = fem
    assert not fits.loc[("fem-p1p1", boundary), "stable"]
    assert fits.loc[("fem-p1p1", boundary), "slope"] > 0.5
    rows = table[(table.method == "fem-p1p1") & (table.boundary == boundary)]
    assert (rows.zero_modes > 0).all()


def test_dirichlet_subspace_of_efg_vanishes_on_the_whole_boundary():
    case = square(9)
    s, nodes, loop = case.efg, case.nodes(), case.boundary_loop()
    edges = segment_edges(nodes, loop, case.geometry)

    def values(points):
        return ShapeFunctions.build(nodes, points, s.weight_u, s.scale_u).phi.toarray()

    Z = sla.null_space(values(boundary_points(nodes, loop, edges, SAMPLES).points),
                       rcond=RCOND)
    dense = values(boundary_points(nodes, loop, edges, 4 * SAMPLES).points) @ Z
    assert Z.shape[1] > 0
    assert np.abs(dense).max() < 1e-10 * np.abs(values(nodes) @ Z).max()


def test_stabilisation_raises_the_schur_complement():
    S, B, T = 2 * sp.eye(2), sp.csr_matrix([[1.0, 0.0], [0.0, 0.0]]), sp.eye(2)
    assert inf_sup(S, B, T) == (pytest.approx(np.sqrt(0.5)), 1)
    beta, zero = inf_sup(S, B, T, C=0.1 * sp.eye(2))
    assert zero == 0 and beta == pytest.approx(np.sqrt(0.1))


def test_command_writes_the_table_and_its_figure(tmp_path, capsys):
    out = tmp_path / "infsup.csv"
    assert main(["infsup", "--methods", "fem-p1p1,efg", "--sizes", "3,5",
                 "--boundary", "free", "--set", "efg.weight_p=exp:0.5",
                 "--out", str(out)]) == 0
    table = pd.read_csv(out, keep_default_na=False)
    assert list(table.columns) == ["method", "weights", "scale_u", "scale_p", "boundary",
                                   "n", "h", "beta", "zero_modes"]
    assert set(table.weights) == {"ElementTriP1/ElementTriP1", "quartic/exp:0.5+perturbation"}
    assert (table.boundary == "free").all() and (tmp_path / "infsup.png").stat().st_size
    assert "wrote" in capsys.readouterr().out


@pytest.mark.parametrize("args,word", [
    (["--methods", "fem-p9"], "fem-p9"),
    (["--sizes", "2,5"], "--sizes"),
    (["--sizes", "5,x"], "--sizes"),
    (["--methods", "fem-th", "--sizes", "100000"], "GiB for the test's dense matrices"),
    (["--set", "efg.weight_u=exp:0"], "efg.weight_u"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, word):
    out = tmp_path / "infsup.csv"
    assert main(["infsup", "--out", str(out), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and word in err[0]
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", ["perturbation", "projection"])
def test_equal_order_efg_decays_and_its_stabilisation_levels_off(kind):
    sizes = (5, 9, 13, 17)
    plain = slopes(measure(["efg"], sizes, overrides=["efg.stabilisation=none"])
                   ).set_index("boundary")
    stable = slopes(measure(["efg"], sizes, overrides=[f"efg.stabilisation={kind}"]))
    assert not plain.stable.any() and (plain.slope > 0.5).all()
    assert stable.stable.all()
