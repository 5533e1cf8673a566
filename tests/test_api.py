"""The Python API as users call it: soilwater.load_case, Case.replace, soilwater.solve and
the Result (history with units, fields as meshio meshes, the resolved case)."""

import dataclasses
import json
import subprocess
import sys

import meshio
import numpy as np
import pandas as pd
import pytest

import soilwater
from soilwater.references.closed_forms import terzaghi, undrained_pressure

#: Terzaghi in ten steps to t = 5 s (c_v t / h^2 = 0.7): well under a second or two.
FAST = ("time.steps=10", "time.end=5.0")


@pytest.fixture(scope="module", params=["efg", "fem-th"])
def result(request):
    return soilwater.solve(soilwater.load_case("terzaghi", *FAST), request.param,
                           progress=False)


def test_solved_terzaghi_pore_pressure_matches_the_series_solution(result):
    case = result.case
    material, fluid = case.material(), case.fluid
    load = -case.boundary.top.traction[1]
    args = (load, case.geometry.height, material.constrained_modulus(), fluid.biot_alpha,
            fluid.storage, fluid.mobility)
    names = [f"p{i}" for i in range(10)]
    z = np.array([dict((p.name, p.point) for p in case.probes)[n][1] for n in names])
    last = result.history.iloc[-1]
    exact, settlement = terzaghi(z, last.time, *args)
    p0 = undrained_pressure(load, *args[2:5])
    computed = last[[f"p_w@{n}" for n in names]].to_numpy(float)
    assert last.time == 5.0
    assert np.abs(computed - exact).max() < 0.06 * p0   # about 3 % on this coarse run
    assert last.settlement == pytest.approx(settlement, rel=0.03)


def test_history_is_a_dataframe_with_a_unit_per_column(result):
    assert isinstance(result.history, pd.DataFrame)
    assert list(result.units) == list(result.history.columns)
    assert all(result.units.values()), [c for c, u in result.units.items() if not u]
    assert (result.units["time"], result.units["p"], result.units["settlement"],
            result.units["p_w@p0"], result.units["eps_a"]) == ("s", "kPa", "m", "kPa", "-")


def test_fields_are_meshio_meshes_as_written_with_the_units(result, tmp_path):
    mesh = result.mesh()
    assert isinstance(mesh, meshio.Mesh)
    last = result.snapshots[-1]
    n = len(last.points)                       # then fem-th's mid-side nodes
    assert np.array_equal(mesh.points[:n, :2], last.points)
    assert np.array_equal(mesh.point_data["p_w"][:n], last.point_data["p_w"])
    assert result.snapshots[0].time == 0.0 and not result.mesh(0).point_data["p_w"].any()
    early = result.mesh(1)      # the first level after the load: the most pressure
    assert early.point_data["p_w"].max() > 2 * mesh.point_data["p_w"].max() > 0
    out = result.write(tmp_path / "run")
    assert json.loads((out / "summary.json").read_text())["history_units"] == result.units
    assert list(pd.read_csv(out / "history.csv").columns) == list(result.units)
    written = meshio.read(out / "fields_0001.vtu")
    assert np.allclose(written.points, early.points)
    assert np.allclose(written.point_data["p_w"], early.point_data["p_w"])


def test_result_keeps_the_resolved_case(result):
    assert result.case == soilwater.load_case("terzaghi", *FAST)
    assert result.case.time.steps == 10 and result.case.fluid.permeability == 1.5


def test_load_case_takes_overrides_as_arguments_a_list_or_a_keyword():
    by_args = soilwater.load_case("terzaghi", "time.steps=4", "time.end=2.0")
    assert soilwater.load_case("terzaghi", ["time.steps=4", "time.end=2.0"]) == by_args
    assert soilwater.load_case("terzaghi", overrides=("time.steps=4", "time.end=2.0")) \
        == by_args
    assert by_args.times().tolist() == [0.0, 0.5, 1.0, 1.5, 2.0]


def test_load_case_and_replace_validate_a_changed_case():
    case = soilwater.load_case("terzaghi")
    changed = case.replace("material.permeability=1e-6")
    assert changed.fluid.permeability == 1e-6 and case.fluid.permeability == 1.5
    assert soilwater.load_case(case, "material.permeability=1e-6") == changed
    for change in (lambda: case.replace("material.permeability=-1e-6"),
                   lambda: soilwater.load_case(case, "material.permeability=-1e-6")):
        with pytest.raises(soilwater.InputError) as err:
            change()
        message = str(err.value)
        assert "\n" not in message and message.startswith("material.permeability")
        assert ">= 0" in message


def test_replace_changes_a_resolved_cases_model_and_names_what_it_needs():
    """A resolved Cam-clay case (its parameters written out) switched to elastic drops
    the Cam-clay keys and asks for E; with E it is the elastic skeleton, keeping nu, e0
    and p0; and back to Cam-clay the same way."""
    case = soilwater.load_case("strip-footing")
    with pytest.raises(soilwater.InputError, match="model 'elastic' needs E"):
        case.replace("material.model=elastic")
    elastic = case.replace("material.model=elastic", "material.E=100")
    assert (elastic.material().E, elastic.material().nu) == (100.0, 0.333)
    with pytest.raises(soilwater.InputError, match="needs lambda, kappa, M"):
        elastic.replace("material.model=modified")
    assert case.replace("material.model=modified").material().model == "modified"


def test_dataclasses_replace_skips_validation_which_replace_does_not():
    case = soilwater.load_case("terzaghi")
    fluid = dataclasses.replace(case.fluid, permeability=-1.0)
    unchecked = dataclasses.replace(case, fluid=fluid)      # accepted, unvalidated
    with pytest.raises(soilwater.InputError, match="material.permeability"):
        soilwater.load_case(unchecked)


def test_solve_accepts_a_case_name():
    result = soilwater.solve("patch-test", "efg", progress=False)
    assert result.method == "efg" and result.case.name == "patch-test"


def test_an_unknown_method_is_one_line_naming_the_methods():
    with pytest.raises(soilwater.InputError) as err:
        soilwater.solve(soilwater.load_case("terzaghi"), "fem-q9")
    message = str(err.value)
    assert "\n" not in message and "'fem-q9'" in message
    assert all(method in message for method in soilwater.METHODS)
    assert {"efg", "fem-th"} <= set(soilwater.METHODS)


def test_the_harness_uses_the_library_methods():
    from soilwater import methods
    from soilwater.studies.harness import runner

    assert runner.solver is methods.solver


@pytest.mark.parametrize("check", [
    "import matplotlib; before = matplotlib.get_backend(); import soilwater; "
    "assert matplotlib.get_backend() == before, (before, matplotlib.get_backend())",
    "import soilwater; assert 'matplotlib.pyplot' not in sys.modules",
    "import soilwater; assert 'matplotlib' not in sys.modules",
    "import soilwater; assert 'soilwater.studies' not in sys.modules; "
    "assert not [m for m in sys.modules if m.startswith('soilwater.studies')]",
])
def test_import_soilwater_leaves_matplotlib_and_the_studies_alone(check):
    proc = subprocess.run([sys.executable, "-c", f"import sys; {check}"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr


def test_efg_paper_runs_the_papers_configuration_and_names_it():
    case = soilwater.load_case("terzaghi", "time.steps=2", "time.end=0.1")
    paper = soilwater.solve(case, "efg-paper", progress=False)
    default = soilwater.solve(case, "efg", progress=False)
    assert paper.case.efg.integration == "paper"
    assert (paper.case.efg.essential, paper.case.efg.stabilisation) == ("penalty", "none")
    assert default.summary["configuration"] == "recommended"
    assert default.case.efg == case.efg


def test_efg_paper_refuses_a_setting_it_would_replace():
    settings = soilwater.efg.settings
    third = next(scheme for scheme in settings.INTEGRATIONS
                 if scheme not in ("paper", settings.RECOMMENDED["integration"]))
    case = soilwater.load_case("terzaghi", f"efg.integration={third}")
    with pytest.raises(soilwater.InputError, match="efg.integration = .* efg-paper sets it"):
        soilwater.solve(case, "efg-paper", progress=False)


@pytest.mark.parametrize("call, message", [
    (lambda: soilwater.load_case(None), "load_case: name_or_path must be .* not NoneType"),
    (lambda: soilwater.load_case(3.5), "load_case: name_or_path must be .* not float"),
    (lambda: soilwater.solve(42, "efg"), "solve: case must be a Case .* not int"),
    (lambda: soilwater.solve("terzaghi", None), "solve: method must be a method name .* "
                                                "not NoneType")])
def test_api_misuse_is_a_type_error_naming_the_argument(call, message):
    with pytest.raises(TypeError, match=message):
        call()


def test_builtin_cases_lists_names_without_loading_them(monkeypatch):
    """Listing the built-in cases reads no case; looking one up reads that one."""
    from soilwater.case import loader

    loaded = []
    read = loader._read_toml
    monkeypatch.setattr(loader, "_read_toml", lambda *a: loaded.append(a[1]) or read(*a))
    cases = soilwater.builtin_cases()
    assert "terzaghi" in list(cases) and len(cases) == len(list(cases))
    assert len(repr(cases)) < 400 and loaded == []
    assert cases["terzaghi"].name == "terzaghi" and loaded == ["terzaghi"]


def test_a_snapshots_mesh_carries_its_time(result):
    for i in (0, -1):
        mesh = result.mesh(i)
        assert mesh.field_data["TimeValue"].tolist() == [result.snapshots[i].time]


@pytest.mark.parametrize("call, message", [
    (lambda: soilwater.load_case("terzaghi", 5), "overrides are strings .* not int"),
    (lambda: soilwater.load_case("terzaghi", {"time.end": 1}), "overrides are strings .* "
                                                               "not dict"),
    (lambda: soilwater.load_case("terzaghi").replace(5), "an override must be a string")])
def test_overrides_of_the_wrong_type_are_a_type_error(call, message):
    with pytest.raises(TypeError, match=message):
        call()
