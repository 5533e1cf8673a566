"""Several soils in one case: ``[material.NAME]`` on the physical surfaces of a mesh
(soilwater.case.regions, soilwater.material.regions), checked against closed forms."""

import json
import re

import numpy as np
import pytest

import soilwater
from soilwater.case.validation import case_from_dict
from soilwater.errors import InputError
from soilwater.physics.geostatic import buoyant_weight, initial_state
from test_mesh_geometry import write_msh


def layered_column(path, nx=3, ny=21, height=10.0, interface=4.0):
    """A column 1 m wide on a structured triangle mesh: region ``clay`` below
    ``interface`` [m], ``crust`` above; physical curves bottom, right, top, left."""
    x, y = np.linspace(0, 1, nx), np.linspace(0, height, ny)
    points = np.stack(np.meshgrid(x, y), -1).reshape(-1, 2)
    k = (np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)[None, :]).ravel()
    triangles = np.vstack([np.column_stack([k, k + 1, k + 1 + nx]),
                           np.column_stack([k, k + 1 + nx, k + nx])])
    loop = np.r_[np.arange(nx), np.arange(1, ny) * nx + nx - 1,
                 (ny - 1) * nx + np.arange(nx)[-2::-1], np.arange(ny - 2, 0, -1) * nx]
    ends = np.stack([loop, np.roll(loop, -1)], 1)
    mid = points[ends].mean(axis=1)
    side = np.select([np.isclose(mid[:, 1], 0), np.isclose(mid[:, 1], height),
                      np.isclose(mid[:, 0], 0)], ["bottom", "top", "left"], "right")
    centre = points[triangles].mean(axis=1)[:, 1]
    write_msh(path, points, triangles, {n: ends[side == n] for n in
                                        ("bottom", "right", "top", "left")},
              {"clay": centre < interface, "crust": centre >= interface})
    return path


def oedometer(path, **material):
    return case_from_dict({
        "geometry": {"mesh": str(path)},
        "material": {"model": "elastic", "E": 1000.0, "nu": 0.3, "permeability": 1e-6,
                     "crust": {"E": 5000.0, "permeability": 1e-5}, **material},
        "boundary": {"bottom": {"displacement": "fixed"},
                     "left": {"displacement": "roller"},
                     "right": {"displacement": "roller"},
                     "top": {"traction": [0.0, -10.0], "water": "drained"}},
        "time": {"end": 1e7, "dt0": 1.0, "growth": 1.5, "dt_max": 2e6},
        "probes": {"clay": [0.5, 2.0], "crust": [0.5, 7.0]}})


@pytest.mark.parametrize("method, tol", [("fem-th", 0.01), ("fem-p1p1-stab", 0.01),
                                         ("efg", 0.02), ("efg-paper", 0.05)])
def test_two_layer_oedometer_settles_as_its_layers_add_up(tmp_path, method, tol):
    """Clay (E = 1000 kPa, 4 m) under a crust five times stiffer (6 m), 10 kPa on the
    drained top: consolidated, the column settles q (h1 / M1 + h2 / M2) = 38.6 mm (M the
    constrained moduli; 0.4 % strain, finite strain within 0.3 %) and the probe at 7 m
    (uy@crust) by the 4 m of clay and 3 m of crust below it, and the first level
    leaves the load on the water in both layers. EFG's smooth shape functions cannot
    follow the kink of the displacement at the interface: measured 1.4 % off (efg, the
    mesh's triangles as cells) and 3.2 % (efg-paper, region carried by the nodes), fem-th
    0.3 %; the tolerances are those, rounded up."""
    case = oedometer(layered_column(tmp_path / "column.msh"))
    history = soilwater.solve(case, method, progress=False).history

    def constrained(E, nu=0.3):
        return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))

    exact = 10.0 * (4.0 / constrained(1000.0) + 6.0 / constrained(5000.0))
    assert history["settlement"].iloc[-1] == pytest.approx(exact, rel=tol)
    below = 10.0 * (4.0 / constrained(1000.0) + 3.0 / constrained(5000.0))  # y = 7 m
    assert -history["uy@crust"].iloc[-1] == pytest.approx(below, rel=tol)
    assert abs(history["ux@crust"].iloc[-1]) < 1e-3 * below
    if method != "efg-paper":
        assert history["p_w@clay"].iloc[0] == pytest.approx(10.0, rel=0.01)
        assert history["p_w@crust"].iloc[0] == pytest.approx(10.0, rel=0.01)


def test_each_point_takes_its_regions_soil_and_permeability(tmp_path):
    case = oedometer(layered_column(tmp_path / "column.msh"))
    material = case.material()
    assert material.names == ("clay", "crust")
    assert [m.E for m in material.materials] == [1000.0, 5000.0]
    assert material.permeability == (1e-6, 1e-5)
    _, state = initial_state(case, material, [[0.5, 1.0], [0.5, 9.0]])
    assert state["region"].tolist() == [0.0, 1.0]
    result = soilwater.solve(case.replace("time.end=1.0", "time.steps=1"), "fem-th",
                             progress=False)
    k = result.mesh().point_data["k"]
    assert set(np.round(k, 12)) == {1e-6, 1e-5}


def test_a_layered_geostatic_start_is_on_each_layers_line(tmp_path):
    """Modified Cam-clay: a crust (lambda 0.1, e = 1.0 at 10 kPa) over soft clay (lambda
    0.4, e = 2.4 at 10 kPa) under gravity and 20 kPa: sigma'_v grows by each depth's
    buoyant weight and is continuous through the interface, and each point's void ratio
    lies on its own layer's normal compression line."""
    clay = {"model": "modified", "lambda": 0.4, "kappa": 0.04, "M": 1.2, "nu": 0.3,
            "e_ref": 2.4, "sigma_v_ref": 10.0}
    data = {"geometry": {"mesh": str(layered_column(tmp_path / "column.msh"))},
            "material": {**clay, "permeability": 1e-9,
                         "crust": {"lambda": 0.1, "kappa": 0.02, "e_ref": 1.0}},
            "gravity": {"g": 9.81},
            "initial": {"stress": "geostatic", "surcharge": 20.0},
            "boundary": {"bottom": {"displacement": "fixed"},
                         "left": {"displacement": "roller"},
                         "right": {"displacement": "roller"},
                         "top": {"water": "drained"}},
            "time": {"end": 1.0, "steps": 1}}
    case = case_from_dict(data)
    y = np.linspace(0.0, 10.0, 401)
    stress, state = initial_state(case, case.material(), np.column_stack([0 * y + 0.5, y]))
    sv = -stress[:, 1]
    assert sv[-1] == pytest.approx(20.0)
    slope = -np.gradient(sv, y)
    weight = buoyant_weight(case, state["v"])
    inside = np.abs(y - 4.0) > 0.1
    np.testing.assert_allclose(slope[1:-1][inside[1:-1]], weight[1:-1][inside[1:-1]],
                               rtol=1e-3)
    e, crust, clay = state["v"] - 1, y > 4.0, y < 4.0    # the interface: either
    np.testing.assert_allclose(e[crust], 1.0 - 0.1 * np.log(sv[crust] / 10.0), atol=1e-9)
    np.testing.assert_allclose(e[clay], 2.4 - 0.4 * np.log(sv[clay] / 10.0), atol=1e-9)


@pytest.mark.parametrize("change, message", [
    ({"fill": {"E": 1.0}}, "material.fill: regions are the physical surfaces of "
                           "geometry.mesh (clay, crust)"),
    ({"crust": {"gamma_w": 10.0}}, "material.crust.gamma_w: the water and the solids' "
                                   "weight are the case's"),
    ({"crust": {"nu": 0.7}}, "material.crust: material.nu = 0.7 must lie in (-1, 0.5)"),
    ({"crust": {"permeability": -1.0}}, "material.crust.permeability = -1.0 must be >= 0"),
])
def test_bad_regions_are_refused_in_one_line(tmp_path, change, message):
    path = layered_column(tmp_path / "column.msh")
    base = {"model": "elastic", "E": 1000.0, "nu": 0.3, **change}
    with pytest.raises(InputError, match=re.escape(message)):
        _with_material(path, base)


def _with_material(path, material):
    case = oedometer(path)
    data = case.to_dict()
    data["material"] = {**material, "permeability": 1e-6}
    return case_from_dict(data)


def test_regions_need_a_mesh():
    with pytest.raises(InputError, match="a rectangle has one material"):
        soilwater.load_case("terzaghi", ("material.crust.E=5.0",))


@pytest.mark.parametrize("method", ["efg", "efg-paper", "fem-th", "fem-p1p1-stab"])
def test_result_files_carry_each_cells_region_as_an_integer_with_its_name(tmp_path,
                                                                          method):
    """The VTU field ``region`` is cell data, an integer index into the mesh's region
    names in ``summary.json`` (``provenance.mesh.regions``): on the layered column each cell is clay below 4 m and crust above (by
    its initial centre), never a smoothed value between the two."""
    case = oedometer(layered_column(tmp_path / "column.msh")).replace(
        "time.end=10", "time.dt0=5", "time.dt_max=5")
    result = soilwater.solve(case, method, progress=False)
    mesh = result.mesh()
    assert "region" not in mesh.point_data
    region = mesh.cell_data["region"][0]
    assert region.dtype.kind == "i"
    (cells,) = [block.data for block in mesh.cells]
    initial = (mesh.points - mesh.point_data["u"])[cells[:, :3], 1].mean(axis=1)
    summary = json.loads((result.write(tmp_path / "run") / "summary.json").read_text())
    names = np.array(summary["provenance"]["mesh"]["regions"])[region]
    assert set(names) == {"clay", "crust"}
    assert np.array_equal(names == "crust", initial >= 4.0)
    assert summary["field_units"]["region"] == "-"
