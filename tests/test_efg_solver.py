"""Coupled u-p EFG solver on the paper's problems and the verification cases."""

import numpy as np
import pytest

from soilwater.cli import main
from soilwater.studies.harness.metrics import (axis_profile, mandel_errors, oscillation_index,
                                               path_error, terzaghi_errors)
from soilwater.efg.solver import solve
from soilwater.case.loader import load_case
from soilwater.targets import MARKER


@pytest.fixture(scope="module")
def compression():
    """Unconfined compression, Delaunay cells, the built-in 100 steps to 20 %."""
    return solve(load_case("unconfined-compression"), progress=False)


def test_unconfined_compression_follows_the_driver(compression):
    history = compression.history
    assert history.eps_a.iloc[-1] == pytest.approx(0.2, rel=1e-6)
    assert path_error(history, compression.case.material()) < 0.01
    assert history.err.max() < 1e-3  # nodal stretching D22 of paper eq. 1


def test_halving_the_time_step_changes_the_path_by_less_than_half_a_percent(compression):
    fine = solve(load_case("unconfined-compression", ["time.steps=200"]), progress=False)
    coarse, fine = compression.history, fine.history.iloc[1::2].reset_index(drop=True)
    np.testing.assert_allclose(coarse.time, fine.time)
    p0 = compression.case.material().p0
    assert max(np.abs(coarse.p - fine.p).max(), np.abs(coarse.q - fine.q).max()) < 0.005 * p0


def test_a_stiff_penalty_converges_within_round_off():
    """Penalty 1e10: the boundary rows carry round-off of about 1e-6 of the force scale,
    above the tolerance; the residual is judged beyond that level, so the step converges
    (it failed after six halvings before) and agrees with the default penalty's."""
    grid = ["discretisation.nx=13", "discretisation.ny=17", "discretisation.layout=grid",
            "time.steps=1", "time.end=0.2"]
    stiff, default = (solve(load_case("unconfined-compression", grid + [f"efg.penalty={a}"]),
                            progress=False) for a in (1e10, 1e6))
    assert stiff.history.iterations.iloc[0] <= 6
    assert stiff.history.q.iloc[0] == pytest.approx(default.history.q.iloc[0], rel=1e-5)


def test_simple_shear_follows_the_driver():
    result = solve(load_case("simple-shear", ["time.steps=50"]), progress=False)
    assert result.history.gamma.iloc[-1] == pytest.approx(0.3, rel=1e-6)
    assert path_error(result.history, result.case.material(), "undrained-simple-shear") < 0.01


def test_terzaghi_matches_the_series_solution():
    result = solve(load_case("terzaghi", ["discretisation.nx=5", "discretisation.ny=41"]),
                   progress=False)
    errors = terzaghi_errors(result)
    assert errors["max_error_load_after_0.1"] < 0.02
    assert errors["settlement_error_after_0.1"] < 0.01


def test_mandel_shows_the_mandel_cryer_rise():
    errors = mandel_errors(solve(load_case("mandel"), progress=False))
    assert errors["peak_centre_exact"] > 1.05
    assert errors["peak_centre"] > 1.05
    assert errors["max_error"] < 0.05


def test_soil_column_oscillation_grows_with_the_stability_number():
    """h^2/(c_v dt) of 30 (built-in) against 3000 (k / 100): oscillations grow."""
    index = []
    for k in (1e-5, 1e-7):
        result = solve(load_case("soil-column", [f"material.permeability={k}",
                                                 "time.end=200.0"]), progress=False)
        index.append(oscillation_index(axis_profile(result, 1)[1], 1.0))
    assert np.isfinite(index).all() and index[1] > index[0] > 0


@pytest.mark.parametrize("overrides,word", [
    (["efg.scale_u=0.6", "efg.cells=squares", "efg.integration=paper"], "efg.scale_u"),
    (["material.permeability=-1e-6"], "permeability"),
    (["loading.velocity_gradient=[[0.0,0.0],[0.0,-3.0]]", "time.steps=1",
      "time.end=1.0"], "failed after 6 halvings"),
])
def test_bad_runs_leave_the_output_folder_untouched(tmp_path, capsys, overrides, word):
    out = tmp_path / "run"
    out.mkdir()
    (out / "previous.txt").write_text("kept")
    (out / MARKER).write_text('{"files": ["previous.txt"]}\n')  # a previous result
    args = ["run", "unconfined-compression", "--method", "efg", "--out", str(out)]
    status = main(args + sum((["--set", o] for o in overrides), []))
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and word in err[0]
    assert [p.name for p in tmp_path.iterdir()] == ["run"]
    assert sorted(p.name for p in out.iterdir()) == sorted([MARKER, "previous.txt"])
