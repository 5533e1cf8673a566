"""Material presets and the factory that builds a material from a TOML table.

A material table names a ``model`` (``original``, ``modified`` or ``elastic``), may
start from a ``preset`` and overrides any of its entries. Cam-clay keys: ``lambda``,
``kappa`` (or the oedometer's compression and swelling indices ``Cc``, ``Cr``, slopes per
decade of stress, which are ``lambda ln 10`` and ``kappa ln 10``), ``M``, ``nu``, ``e0``,
``p0``, ``ocr``, ``G``; elastic keys: ``E`` (or the oedometric compressibility ``mv``,
a constant-m_v skeleton), ``nu``, ``p0``, ``e0``. Unknown keys are an error, and so is a
missing one, by name.
"""

import math
import tomllib
from dataclasses import replace
from pathlib import Path

from soilwater.material.camclay import MODELS, CamClay
from soilwater.material.elastic import LinearElastic
from soilwater.errors import InputError, require

#: The paper's Table 1 (Cam-clay); p'0 = 3.0 in the case's stress unit.
PRESETS = {
    "table1": {"lambda": 0.11, "kappa": 0.04, "M": 1.42, "nu": 0.333, "e0": 0.83, "p0": 3.0},
}

_CAMCLAY_KEYS = {"lambda": "lam", "kappa": "kappa", "M": "M", "nu": "nu", "e0": "e0",
                 "p0": "p0", "ocr": "ocr", "G": "G", "e_ref": "e_ref",
                 "sigma_v_ref": "sigma_v_ref"}
_ELASTIC_KEYS = {"E": "E", "nu": "nu", "p0": "p0", "e0": "e0"}


def material_from_spec(spec):
    """Build a material from a mapping such as a TOML ``[material]`` table.

    Parameters
    ----------
    spec : mapping
        ``model`` (default ``original``), optional ``preset`` and parameter keys.
        Keys that describe the pore fluid and the weight (:data:`FLUID_KEYS`) are
        ignored here; :mod:`soilwater.case.model` reads them. ``model =
        "elastic"`` with a Cam-clay preset is the linear elastic skeleton with the
        preset's initial moduli (``K = v0 p'0 / kappa`` and its ``nu``), p'0 and e0, for
        comparing a skeleton that cannot yield with the clay; explicit ``E``, ``nu`` or
        ``p0`` replace them.

    Returns
    -------
    CamClay or LinearElastic

    Examples
    --------
    >>> material_from_spec({"preset": "table1", "model": "modified"}).model
    'modified'
    >>> round(material_from_spec({"preset": "table1", "model": "elastic"}).E, 3)
    137.524
    """
    spec = {k: v for k, v in spec.items() if k not in FLUID_KEYS}
    model = spec.pop("model", "original")
    require(model in ("elastic", *MODELS), f"material.model = {model!r} is unknown: use "
            f"one of {', '.join(('elastic', *MODELS))}")
    preset = spec.pop("preset", None)
    values = {}
    if preset is not None:
        require(preset in PRESETS, f"material.preset = {preset!r} is unknown: "
                f"use one of {', '.join(PRESETS)}")
        values.update(PRESETS[preset])
        if model == "elastic" and "kappa" in values:
            values = _initial_elasticity(values)
    if model == "elastic":
        require(not {"E", "mv"} <= set(spec), "material: give E or mv, not both (mv = "
                "1 / the constrained modulus)")
        if "mv" in spec:
            values.pop("E", None)           # a preset's modulus gives way
        values = _compressibility({**values, **spec})
    else:
        values.update(_indices(spec))
    keys = _ELASTIC_KEYS if model == "elastic" else _CAMCLAY_KEYS
    unknown = sorted(set(values) - set(keys))
    require(not unknown, f"material: unknown key(s) {', '.join(unknown)} for model "
            f"{model!r}: allowed are {', '.join(keys)}"
            + (", mv" if model == "elastic" else ", Cc, Cr")
            + f" (and in a case {', '.join(FLUID_KEYS)})")
    needed = _ELASTIC_NEEDS if model == "elastic" else _CAMCLAY_NEEDS
    missing = [k for k in needed if k not in values]
    if model != "elastic" and not {"e_ref", "sigma_v_ref"} & set(values):
        missing += [k for k in ("e0", "p0") if k not in values]
    line = " or anchor its compression line (e_ref, sigma_v_ref)" if {"e0", "p0"} & set(
        missing) and model != "elastic" else ""
    require(not missing, f"material: model {model!r} needs {', '.join(missing)}: set "
            f"{'it' if len(missing) == 1 else 'them'} in [material]{line} (or start from a "
            f"preset, e.g. preset = \"table1\")")
    kwargs = {keys[k]: v for k, v in values.items()}
    if model == "elastic":
        return LinearElastic(**kwargs)
    require(("e_ref" in values) == ("sigma_v_ref" in values), "material.e_ref and "
            "material.sigma_v_ref anchor the compression line together: set both or neither")
    start = {"e0": values.get("e_ref"), "p0": values.get("sigma_v_ref")}
    require(start["e0"] is None or min(start.values()) > 0, f"material.e_ref = "
            f"{start['e0']} and sigma_v_ref = {start['p0']} must be positive (a void ratio, "
            "and kPa compression positive)")
    return _on_line(CamClay(model=model, **{**start, **kwargs}), values)


def _on_line(clay, values):
    """``clay`` with p'0 and e0 on its anchored compression line where not given: p'0 =
    ``sigma_v_ref`` and e0 that of the state ``(p'0, ocr p'0)`` on the line."""
    if "e0" in values and "p0" in values:
        return clay
    p0 = values.get("p0", clay.sigma_v_ref)
    v0 = clay.volume(p0, clay.ocr * p0, clay.anchor)
    return replace(clay, p0=float(p0), e0=float(values.get("e0", v0 - 1)))


def model_keys(model):
    """The ``[material]`` skeleton keys that ``model`` takes (``elastic`` or a Cam-clay
    model), aliases included.

    Examples
    --------
    >>> sorted(model_keys("elastic"))
    ['E', 'e0', 'mv', 'nu', 'p0']
    """
    if model == "elastic":
        return {*_ELASTIC_KEYS, "mv"}
    return {*_CAMCLAY_KEYS, *_INDICES}


#: Keys each model needs (the others have defaults: ``ocr`` 1, ``G`` from ``nu``, an
#: elastic skeleton's ``p0`` and ``e0``, a Cam-clay's ``e0`` and ``p0`` on the line
#: anchored by ``e_ref`` and ``sigma_v_ref``).
_CAMCLAY_NEEDS = ("lambda", "kappa", "M", "nu")
_ELASTIC_NEEDS = ("E", "nu")
#: The oedometer's indices and the Cam-clay slopes they give: ``Cc = lambda ln 10``.
_INDICES = {"Cc": "lambda", "Cr": "kappa"}


def _compressibility(values):
    """``values`` with the oedometric volume compressibility ``mv`` [1/kPa] turned into
    Young's modulus: the constrained modulus ``E (1 - nu) / ((1 + nu) (1 - 2 nu))`` is
    ``1 / mv``. Under the Jaumann rate, a laterally confined layer then keeps ``d ln(1 +
    e) = -mv d sigma'_v`` at any strain: Xie and Leo's constant-m_v skeleton.

    Examples
    --------
    >>> round(_compressibility({"mv": 1e-3, "nu": 0.3})["E"], 6)
    742.857143
    """
    if "mv" not in values:
        return dict(values)
    require("nu" in values, "material: mv needs nu (the constrained modulus 1/mv sets E "
            "with it)")
    nu, mv = values["nu"], values["mv"]
    require(mv > 0, f"material.mv = {mv} must be positive (1/kPa)")
    require(-1.0 < nu < 0.5, f"material.nu = {nu} must lie in (-1, 0.5)")
    out = {k: v for k, v in values.items() if k != "mv"}
    out["E"] = (1 + nu) * (1 - 2 * nu) / ((1 - nu) * mv)
    return out


def _indices(values):
    """``values`` with ``Cc`` and ``Cr`` turned into ``lambda`` and ``kappa`` (e against
    log10 of stress against e against ln: a factor ln 10).

    Examples
    --------
    >>> _indices({"Cc": 0.2533, "Cr": 0.0921, "M": 1.2})  # doctest: +ELLIPSIS
    {'M': 1.2, 'lambda': 0.1100..., 'kappa': 0.0399...}
    """
    out = {k: v for k, v in values.items() if k not in _INDICES}
    for index, slope in _INDICES.items():
        if index in values:
            require(slope not in values, f"material: give {index} or {slope}, not both "
                    f"({index} = {slope} ln 10)")
            out[slope] = values[index] / math.log(10.0)
    return out


def parameters(material):
    """Every parameter of a material as the ``[material]`` keys that rebuild it:
    ``model`` and each key of its model (``G`` only when given), so a result says which
    material made it.

    Examples
    --------
    >>> parameters(material_from_spec({"preset": "table1"}))
    {'model': 'original', 'lambda': 0.11, 'kappa': 0.04, 'M': 1.42, 'nu': 0.333, 'e0': 0.83, 'p0': 3.0, 'ocr': 1.0}
    >>> material_from_spec(parameters(material_from_spec({"preset": "table1"}))).lam
    0.11
    """
    elastic = not material.plastic
    keys = _ELASTIC_KEYS if elastic else _CAMCLAY_KEYS
    values = {key: getattr(material, attribute) for key, attribute in keys.items()}
    return {"model": "elastic" if elastic else material.model,
            **{k: float(v) for k, v in values.items() if v is not None}}


def _initial_elasticity(clay):
    """``E``, ``nu`` and ``p0`` of a Cam-clay parameter set's initial elastic moduli."""
    K, G = CamClay(**{_CAMCLAY_KEYS[k]: v for k, v in clay.items()}).moduli()
    return {"E": float(9 * K * G / (3 * K + G)),
            "nu": float((3 * K - 2 * G) / (2 * (3 * K + G))), "p0": clay["p0"],
            "e0": clay["e0"]}


#: Fluid keys that may sit in a material table; they belong to the coupled problem.
FLUID_KEYS = ("permeability", "gamma_w", "biot_alpha", "storage", "permeability_law",
              "permeability_e", "permeability_ck", "specific_gravity")


def load_material(name_or_path, **overrides):
    """A preset name (``table1``) or a TOML file with a ``[material]`` table (or bare keys).

    Keyword overrides (``model="modified"``, ``ocr=2``) replace entries.
    """
    path = Path(name_or_path)
    if path.suffix == ".toml" or path.exists():
        require(path.exists(), f"material file {str(path)!r} does not exist")
        with path.open("rb") as fh:
            data = tomllib.load(fh)
        spec = dict(data.get("material", data))
    else:
        require(name_or_path in PRESETS, f"material {name_or_path!r} is neither a preset "
                f"({', '.join(PRESETS)}) nor a TOML file")
        spec = {"preset": name_or_path}
    spec.update({k: v for k, v in overrides.items() if v is not None})
    return material_from_spec(spec)
