"""FEM reference (scikit-fem): block assembly against scikit-fem's own forms, Terzaghi
against MOOSE and the closed form, Cam-clay paths, Mandel's rigid plate, the column's
first-step stability table and clear failures."""

import numpy as np
import pandas as pd
import pytest
import scipy.sparse as sp
from skfem import BilinearForm, CellBasis, ElementTriP1, ElementTriP2, MeshTri

from soilwater.cli import main
from soilwater.studies.harness.metrics import moose_errors, overshoot, path_error
from soilwater.studies.harness.moose import moose_terzaghi
from soilwater.studies.stability.study import column_ratios
from soilwater.fem.assembly import Shapes, block
from soilwater.fem.solver import solve
from soilwater.references.closed_forms import mandel, terzaghi, undrained_pressure
from soilwater.errors import InputError
from soilwater.case.loader import load_case
from soilwater.physics.weakform import Coefficients

LOAD = 1e-3  # the built-in Terzaghi load (MOOSE: 1)
HEIGHTS = np.arange(10.0)


def test_block_of_compact_coefficients_is_scikit_fems_form():
    """A P2 two-field test space against a P1 trial field, coefficients varying per point
    on three of the (f, s, g, t) terms: ``block`` equals scikit-fem's assembled form."""
    mesh = MeshTri().refined(2)
    ub = CellBasis(mesh, ElementTriP2())
    pb = CellBasis(mesh, ElementTriP1(), quadrature=ub.quadrature)
    a, b, c = np.random.default_rng(4).normal(size=(3, *ub.dx.shape))
    coeff = Coefficients.of({(0, 1, 0, 0): (a * ub.dx).ravel(),
                             (0, 0, 0, 2): (b * ub.dx).ravel(),
                             (1, 2, 0, 1): (c * ub.dx).ravel()}, (2, 1))
    K = block(Shapes.of(ub), Shapes.of(pb), coeff)
    ux = BilinearForm(lambda p, v, w: w.a * v.grad[0] * p + w.b * v * p.grad[1])
    uy = BilinearForm(lambda p, v, w: w.c * v.grad[1] * p.grad[0])
    reference = sp.vstack([ux.assemble(pb, ub, a=a, b=b), uy.assemble(pb, ub, c=c)])
    assert K.shape == reference.shape == (2 * ub.N, pb.N)
    assert abs(K - reference).max() < 1e-12 * abs(reference).max()


def _terzaghi_run(method, overrides=()):
    """p_w/load at the probes p0..p9, settlement/load of the top, and the exact p0/load."""
    case = load_case("terzaghi", list(overrides))
    result = solve(case, method, progress=False)
    h = result.history
    p = h[[f"p_w@p{k}" for k in HEIGHTS.astype(int)]].to_numpy() / LOAD
    top = case.nodes()[:, 1] == case.geometry.height
    settlement = np.array([-s.point_data["u"][top, 1].mean() for s in result.snapshots[1:]])
    fluid, mat = case.fluid, case.material()
    modulus = mat.constrained_modulus()
    exact = [terzaghi(HEIGHTS, t, 1.0, 10.0, modulus, fluid.biot_alpha, fluid.storage,
                      fluid.mobility) for t in h.time]
    p0 = undrained_pressure(1.0, modulus, fluid.biot_alpha, fluid.storage)
    return (h.time.to_numpy(), p, settlement / LOAD, np.array([e[0] for e in exact]),
            np.array([e[1] for e in exact]), p0)


def test_q1q1_reproduces_moose_terzaghi(peer):
    moose = moose_terzaghi(peer)
    result = solve(load_case("terzaghi"), "fem-q1q1", progress=False)
    errors = moose_errors(result, moose)
    assert errors["pressure_after_0.1"] < 0.01
    assert errors["settlement_after_0.1"] < 0.005
    _, p, _, _, _, p0 = _terzaghi_run("fem-q1q1")
    assert overshoot(p[0], p0) > 0.2  # MOOSE: +0.38


@pytest.mark.parametrize("method", ["fem-th", "fem-p1p1-stab"])
def test_terzaghi_against_the_closed_form(method):
    # On MOOSE's steps (dt up to 0.1, c_v dt / h^2 = 1.4) backward Euler alone errs by
    # 0.024 p0 at t ~ 0.2 for every element pair (MOOSE's file too): refine dt_max.
    t, p, settlement, p_exact, s_exact, p0 = _terzaghi_run(
        method, ["time.dt_max=0.01", "time.end=2.0"])
    late = t >= 0.1
    assert np.abs(p - p_exact)[late].max() < 0.02 * p0
    assert np.abs(settlement / s_exact - 1)[late].max() < 0.005
    if method == "fem-p1p1-stab":
        assert overshoot(p[0], p0) < 0.02


@pytest.mark.parametrize("name,test", [("unconfined-compression", "undrained-plane-strain"),
                                       ("simple-shear", "undrained-simple-shear")])
def test_cam_clay_paths_follow_the_driver(name, test):
    case = load_case(name)
    result = solve(case, "fem-th", progress=False)
    assert path_error(result.history, case.material(), test) < 0.01
    strain = result.history["gamma" if name == "simple-shear" else "eps_a"].iloc[-1]
    assert strain == pytest.approx(0.3 if name == "simple-shear" else 0.2, rel=1e-9)


def test_mandel_rigid_plate_carries_the_load():
    case = load_case("mandel")
    result = solve(case, "fem-q1q1", progress=False)
    h, mat = result.history, case.material()
    force = -case.plate_force(1.0)
    exact = np.array([mandel([0.0], t, force, 1.0, mat.G, mat.nu, case.fluid.mobility)[0]
                      for t in h.time])
    late = (h.time >= 0.01).to_numpy()
    assert np.abs(h["p_w@centre"] - exact)[late].max() < 0.03 * force / 2
    assert h["p_w@centre"].max() > 1.05 * force / 2  # Mandel-Cryer effect


def test_column_first_step_stability_table():
    table = column_ratios(ratios=(300,), methods={m: (m, ()) for m in
                                                  ("fem-th", "fem-p1p1", "fem-p1p1-stab")})
    worst = table.set_index("method").interior
    assert worst["fem-th"] < worst["fem-p1p1"] / 5
    assert worst["fem-p1p1-stab"] < worst["fem-p1p1"] / 5
    assert table.set_index("method").rating["fem-p1p1"] == "bad"


def test_inverting_mesh_stops_with_one_error_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    status = main(["run", "unconfined-compression", "--method", "fem-p1p1", "--out",
                   str(out), "--set", "loading.velocity_gradient=[[0.0, 0.0], [-100.0, 0.0]]",
                   "--set", "time.end=1.0", "--set", "time.steps=1"])
    err = capsys.readouterr().err
    assert status == 2 and not out.exists()
    assert len(err.strip().splitlines()) == 1
    assert "t = 0 -> 1 s" in err and "inverts" in err


@pytest.mark.parametrize("case,method,word", [("unconfined-compression", "fem-q1q1", "grid"),
                                              ("patch-test", "fem-th", "coupled")])
def test_unsupported_combinations_are_refused(case, method, word):
    with pytest.raises(InputError, match=word):
        solve(load_case(case), method, progress=False)


def test_run_writes_vtu_with_cells(tmp_path):
    import meshio

    out = tmp_path / "run"
    assert main(["run", "terzaghi", "--method", "fem-th", "--out", str(out),
                 "--set", "time.end=0.001"]) == 0
    history = pd.read_csv(out / "history.csv")
    assert list(history.columns[:5]) == ["time", "eps_a", "p", "q", "err"]
    mesh = meshio.read(out / "fields_0001.vtu")
    assert mesh.cells[0].type == "triangle6" and len(mesh.cells[0].data) == 20
    assert {"u", "p_w", "p_eff", "q"} <= set(mesh.point_data)
