"""Validation of the material regions: ``[material.NAME]`` tables on a mesh.

A table ``[material.NAME]`` gives the physical surface ``NAME`` of ``geometry.mesh`` its
own soil: the ``[material]`` skeleton with the table's keys changed (a table that sets
``model`` starts afresh from its own keys, or its ``preset``), and its own
``permeability`` (default the case's). The water and the solids' weight
(``gamma_w``, ``biot_alpha``, ``storage``, the permeability law and its ``permeability_e``
and ``permeability_ck``, ``specific_gravity``) are the case's. A region without a table
takes ``[material]`` whole. :class:`soilwater.material.regions.Regions` is the material
the solvers then read.
"""

from soilwater.case.entries import number, string
from soilwater.errors import InputError, require
from soilwater.material.presets import FLUID_KEYS, material_from_spec, parameters


def read_regions(table, fluid, geometry):
    """Each region's ``(name, spec)``, specs resolved (every skeleton parameter and
    ``permeability``), in the mesh's region order; ``()`` without region tables.

    Parameters
    ----------
    table : dict
        The raw ``[material]`` table (its skeleton keys are what a region inherits, so
        that e0 and p0 derived from one line are derived again from a region's).
    fluid : soilwater.material.fluid.Fluid
        The case's pore fluid.
    geometry : soilwater.case.domain.Geometry
    """
    tables = {name: value for name, value in table.items() if isinstance(value, dict)}
    if not tables:
        return ()
    names = geometry.mesh.regions if geometry.mesh is not None else ()
    base = {key: value for key, value in table.items()
            if key not in FLUID_KEYS and not isinstance(value, dict)}
    for name in tables:
        require(name in names, f"material.{name}: regions are the physical surfaces of "
                f"geometry.mesh ({', '.join(names) or 'a rectangle has one material'}): "
                "name one of them, or give [material] alone")
    return tuple((name, _region(tables.get(name, {}), name, base, fluid))
                 for name in names)


def _region(table, name, base, fluid):
    """The resolved spec of region ``name``: ``base`` changed by its ``table``."""
    where = f"material.{name}"
    common = sorted(set(table) & (set(FLUID_KEYS) - {"permeability"}))
    require(not common, f"{where}.{common[0] if common else ''}: the water and the solids' "
            "weight are the case's, common to every region: set it in [material]")
    for key, value in table.items():
        require(not isinstance(value, dict), f"{where}.{key}: a region takes keys, not "
                "tables")
    own = {key: (string(table, key, where, None) if key in ("model", "preset")
                 else number(table, key, where))
           for key in table if key != "permeability"}
    spec = own if "model" in own or "preset" in own else {**base, **own}
    try:
        spec = parameters(material_from_spec(spec))
    except InputError as err:
        raise InputError(f"{where}: {err}") from None
    permeability = number(table, "permeability", where, fluid.permeability)
    require(permeability >= 0, f"{where}.permeability = {permeability} must be >= 0 (m/s)")
    return tuple(sorted({**spec, "permeability": permeability}.items()))
