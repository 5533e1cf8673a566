"""Problem definitions, the public entry point: load a case by built-in name or TOML file.

:func:`load_case` reads a built-in case (see :func:`builtin_cases`) or a TOML file, applies
``"section.key=value"`` overrides and returns the validated :class:`Case` the solvers
read. The pieces live in four modules:

* :mod:`soilwater.case.model`: the case model, :class:`Case` and its parts (:class:`Geometry`,
  :class:`Boundary`, :class:`TimeStepping`, ...), and the constants that describe it
  (:data:`EDGES`, :data:`KINDS`, ...);
* :mod:`soilwater.efg.settings`: the typed method settings, :class:`EFGSettings` and the MLS
  :class:`Weight` with its name grammar :func:`weight_form`;
* :mod:`soilwater.case.schema`: the TOML schema (its docstring documents every section, key,
  default and load-time bound) and the override parser;
* :mod:`soilwater.case.validation`: :func:`case_from_dict`, which checks a plain dict against the
  schema and builds the Case.

The built-in cases are the TOML files of the package ``cases`` (the repository's
``cases/`` folder), one case per file, named by the file's stem.
"""

import tomllib
from importlib.resources import files
from pathlib import Path

from soilwater.errors import InputError, require
from soilwater.case.schema import apply_override
from soilwater.case.validation import case_from_dict


def builtin_cases():
    """The built-in cases, ``{name: Case}`` in alphabetical order.

    One case per TOML file of the package ``cases``, named by the file's stem (each
    file's ``name`` key, if given, is the same).

    Examples
    --------
    >>> list(builtin_cases())[:3]
    ['cantilever', 'large-strain-column', 'mandel']
    """
    return {name: case_from_dict(_read_toml(entry, name))
            for name, entry in _builtin_files().items()}


def load_case(name_or_path, overrides=()):
    """A built-in case name or a TOML file, with ``"section.key=value"`` overrides.

    Parameters
    ----------
    name_or_path : str or Path
        One of :func:`builtin_cases` or the path of a ``.toml`` file (a file without a
        ``name`` key takes its stem as the name).
    overrides : iterable of str
        Entries such as ``"material.permeability=1e-6"``, applied before validation
        (see :func:`soilwater.case.schema.apply_override`).

    Returns
    -------
    Case

    Raises
    ------
    InputError
        One line naming the bad parameter and the fix.

    Examples
    --------
    >>> load_case("terzaghi", ["time.steps=10"]).times().size
    11
    """
    data = _raw(name_or_path)
    for text in overrides:
        apply_override(data, text)
    return case_from_dict(data)


def _builtin_files():
    """``{stem: resource}`` of the built-in TOML files (``soilwater/case/builtin``), by name."""
    folder = files("soilwater.case") / "builtin"
    entries = {entry.name.removesuffix(".toml"): entry for entry in folder.iterdir()
               if entry.name.endswith(".toml") and entry.is_file()}
    return dict(sorted(entries.items()))


def _raw(name_or_path):
    """The case's plain dict: a parsed built-in file or the parsed TOML file."""
    text = str(name_or_path)
    builtins = _builtin_files()
    if text in builtins:
        return _read_toml(builtins[text], text)
    path = Path(name_or_path)
    require(path.suffix == ".toml" or path.exists(), f"case {text!r} is neither a built-in "
            f"case ({', '.join(builtins)}) nor a TOML file")
    require(path.is_file(), f"case file {text!r} does not exist")
    return _read_toml(path, path.stem, text)


def _read_toml(source, stem, label=None):
    """Parse the TOML file ``source`` (a path or resource); ``name`` defaults to ``stem``."""
    try:
        with source.open("rb") as fh:
            data = tomllib.load(fh)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"case file {label or source.name!r} is not valid TOML: "
                         f"{err}") from None
    data.setdefault("name", stem)
    return data
