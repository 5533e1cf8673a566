"""Load a case by built-in name or TOML file: the entry point of :mod:`soilwater.case`.

:func:`load_case` reads a built-in case (see :func:`builtin_cases`) or a TOML file, applies
``"section.key=value"`` overrides and returns the validated
:class:`~soilwater.case.model.Case` the solvers read. The pieces live in these modules:

* :mod:`soilwater.case.model`: the case model, :class:`~soilwater.case.model.Case` and its
  parts (:class:`~soilwater.case.domain.Geometry`, :class:`~soilwater.case.timeline.TimeStepping`,
  ...); the boundary conditions (:data:`~soilwater.case.boundary.EDGES`,
  :data:`~soilwater.case.boundary.KINDS`, :class:`~soilwater.case.boundary.Boundary`, ...) in
  :mod:`soilwater.case.boundary`, the node grid in :mod:`soilwater.case.grid` and the pore
  fluid in :mod:`soilwater.material.fluid`;
* :mod:`soilwater.efg.settings` and :mod:`soilwater.fem.settings`: the typed method
  settings, :class:`~soilwater.efg.settings.EFGSettings` (with the MLS
  :class:`~soilwater.efg.settings.Weight`) and :class:`~soilwater.fem.settings.FEMSettings`;
* :mod:`soilwater.case.schema`: the TOML schema (its docstring documents every section, key,
  default and load-time bound) and the override parser;
* :mod:`soilwater.case.validation`: :func:`~soilwater.case.validation.case_from_dict`, which
  checks a plain dict against the schema and builds the Case (with
  :mod:`soilwater.case.entries` and :mod:`soilwater.case.boundary_validation`).

The built-in cases are the TOML files of ``soilwater/case/builtin``, one case per file,
named by the file's stem.
"""

import codecs
import tomllib
from collections.abc import Iterable, Mapping
from importlib.resources import files
from os import PathLike
from pathlib import Path

from soilwater.case.model import Case
from soilwater.case.schema import apply_override
from soilwater.case.validation import case_from_dict
from soilwater.errors import InputError, require


def builtin_cases():
    """The built-in cases, a read-only mapping ``{name: Case}`` in alphabetical order; a
    case is read and validated when it is looked up, so listing the names reads nothing.

    One case per TOML file of ``soilwater/case/builtin``, named by the file's stem (each
    file's ``name`` key, if given, is the same).

    Examples
    --------
    >>> list(builtin_cases())[:3]
    ['cantilever', 'embankment', 'large-strain-column']
    >>> builtin_cases()["terzaghi"].name
    'terzaghi'
    """
    return Builtins(_builtin_files())


class Builtins(Mapping):
    """The built-in cases by name (:func:`builtin_cases`): each loaded on lookup."""

    def __init__(self, entries):
        self._entries = entries

    def __getitem__(self, name):
        return case_from_dict(_read_toml(self._entries[name], name))

    def __iter__(self):
        return iter(self._entries)

    def __len__(self):
        return len(self._entries)

    def __repr__(self):
        return f"builtin_cases({', '.join(self._entries)})"


def load_case(name_or_path, *entries, overrides=()):
    """A built-in case name, a TOML file or a case, with ``"section.key=value"`` overrides.

    Parameters
    ----------
    name_or_path : str or Path or Case
        One of :func:`builtin_cases`, the path of a ``.toml`` file (a file without a
        ``name`` key takes its stem as the name) or a :class:`~soilwater.case.model.Case`
        (its :meth:`~soilwater.case.model.Case.to_dict`, validated again).
    *entries : str or iterable of str
        Overrides such as ``"material.permeability=1e-6"``, one per argument or in lists,
        applied in order before validation (see
        :func:`soilwater.case.schema.apply_override`).
    overrides : iterable of str
        More overrides, applied after ``entries``.

    Returns
    -------
    Case

    Raises
    ------
    InputError
        One line naming the bad parameter and the fix.

    Examples
    --------
    >>> load_case("terzaghi", "time.steps=10", "time.end=2.0").times()[-1]
    np.float64(2.0)
    >>> load_case("terzaghi", ["time.steps=10"]).times().size
    11
    >>> load_case("terzaghi", overrides=("material.permeability=-1e-6",))
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: material.permeability = -1e-06 must be >= 0 ...
    """
    if not isinstance(name_or_path, (str, PathLike, Case)):
        raise TypeError(f"load_case: name_or_path must be a built-in case name, a TOML "
                        f"file's path or a Case, not {type(name_or_path).__name__}")
    data = name_or_path.to_dict() if isinstance(name_or_path, Case) else _raw(name_or_path)
    for entry in (*entries, overrides):
        if not isinstance(entry, (str, Iterable)) or isinstance(entry, Mapping):
            raise TypeError(f"load_case: overrides are strings 'section.key=value' or lists "
                            f"of them, e.g. [\"time.end=1\"], not {type(entry).__name__}")
        for text in ([entry] if isinstance(entry, str) else entry):
            apply_override(data, text)
    return case_from_dict(data)


def _builtin_files():
    """``{stem: resource}`` of the built-in TOML files (``soilwater/case/builtin``), by
    name."""
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
    require(text.strip(), "the case is empty: give a built-in case name "
            f"({', '.join(builtins)}) or a TOML file")
    require(path.exists(), f"case file {text!r} does not exist")
    require(path.is_file(), f"case file {text!r} is "
            f"{'a folder' if path.is_dir() else 'not a regular file'}: give a TOML file")
    return _read_toml(path, path.stem, text)


def text(raw, what):
    """``raw`` bytes decoded as UTF-8 (TOML's encoding).

    Raises
    ------
    InputError
        For a byte-order mark or bytes that are not UTF-8, naming ``what``, the byte's
        position (line, column) and the fix.

    Examples
    --------
    >>> text("name = 'caf\u00e9'".encode("latin-1"), "case file 'a.toml'")
    Traceback (most recent call last):
    ...
    soilwater.errors.InputError: case file 'a.toml' is not UTF-8 text: byte 0xe9 at position 11 (line 1, column 12); save it as UTF-8
    """
    require(not raw.startswith(codecs.BOM_UTF8), f"{what} starts with a UTF-8 byte-order "
            "mark (bytes 0-2), which TOML does not allow: save it as UTF-8 without BOM")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw[:err.start].count(b"\n") + 1
        column = err.start - (raw.rfind(b"\n", 0, err.start) + 1) + 1
        raise InputError(f"{what} is not UTF-8 text: byte 0x{raw[err.start]:02x} at "
                         f"position {err.start} (line {line}, column {column}); save it as "
                         "UTF-8") from None


def _read_toml(source, stem, label=None):
    """Parse the TOML file ``source`` (a path or resource); ``name`` defaults to ``stem``,
    and a relative ``geometry.mesh`` is read from the file's folder."""
    label = label or source.name
    with source.open("rb") as fh:
        content = text(fh.read(), f"case file {label!r}")
    try:
        data = tomllib.loads(content)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"case file {label!r} is not valid TOML: {err}") from None
    except ValueError as err:                         # an integer past Python's digits
        raise InputError(f"case file {label!r} holds a number that cannot be read "
                         f"({err.args[0].split(':')[0]}): write it with an exponent, "
                         "e.g. 1e30") from None
    data.setdefault("name", stem)
    geometry = data.get("geometry")
    if isinstance(geometry, dict) and isinstance(geometry.get("mesh"), str):
        geometry["mesh"] = str(Path(str(source)).parent / Path(geometry["mesh"]).expanduser())
    return data
