"""What code a run or a study is made of: the package modules it can import, and a hash of
each that ignores comments, docstrings and layout.

A run's cache key (:func:`soilwater.studies.harness.runner.code_version`) and a study's
record of its sources (:mod:`soilwater.studies.harness.study`) both come from here, so a
section of the report is stale, and a cached run invalid, only when code that could have
executed in it changed.

The modules are found statically: the ``soilwater`` imports of a module, at its top level
and inside its functions, followed transitively (every package ``__init__`` on the way
included). An import inside a function into a solver folder (``efg/``, ``fem/``) that the
caller did not use is not followed, so a study that ran only the finite element pairs does
not depend on the meshless solver's code.
"""

import ast
import hashlib
import importlib.util
from functools import cache
from pathlib import Path

from soilwater.studies.harness.paths import PACKAGE

#: The solver folders; each a dependency only of what runs or imports it.
SOLVERS = ("efg", "fem")
#: Data files the library reads (built-in cases and meshes): every one is a dependency.
DATA = (".toml", ".msh", ".geo")


def module_file(name, outside=()):
    """The source file of module ``name``: a package module (``soilwater.x.y``) under
    :data:`~soilwater.studies.harness.paths.PACKAGE`, or one of a top-level package in
    ``outside`` (a study kept outside the package) found by the import system; else
    None."""
    top = name.split(".")[0]
    if top == "soilwater":
        path = PACKAGE.joinpath(*name.split(".")[1:])
        candidates = (path.with_suffix(".py"), path / "__init__.py")
    elif top in outside:
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            return None
        candidates = [Path(spec.origin)] if spec is not None and spec.origin else []
    else:
        return None
    return next((p for p in candidates if p.suffix == ".py" and p.is_file()), None)


def _imports(name, outside):
    """``(top, lazy)``: the modules ``name`` imports at its top level and inside functions
    (with every parent package) that :func:`module_file` finds."""
    path = module_file(name, outside)
    stat = path.stat()
    return _parse(name, path, stat.st_mtime_ns, stat.st_size, outside)


@cache
def _parse(name, path, mtime, size, outside):
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    top, lazy = set(), set()
    tree = ast.parse(path.read_bytes())
    body = {id(node) for node in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = (".".join(package[:len(package) - node.level + 1]
                             + ([node.module] if node.module else []))
                    if node.level else node.module)
            targets = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        found = {".".join(t.split(".")[:i]) for t in targets
                 for i in range(1, len(t.split(".")) + 1)}
        (top if id(node) in body else lazy).update(
            m for m in found if module_file(m, outside))
    return frozenset(top), frozenset(lazy)


def closure(roots, solvers=SOLVERS):
    """``{module: file}`` of the modules ``roots`` can import, themselves included: every
    top-level import, and imports inside functions except into a solver folder not in
    ``solvers``; package modules, and those of the roots' own top-level packages.

    >>> mods = closure(["soilwater.material.camclay"], solvers=())
    >>> "soilwater.material.camclay" in mods, "soilwater.efg.solver" in mods
    (True, False)
    """
    blocked = tuple(f"soilwater.{s}." for s in SOLVERS if s not in solvers)
    outside = tuple(sorted({r.split(".")[0] for r in roots} - {"soilwater"}))
    seen, todo = set(), [r for r in roots if module_file(r, outside)]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        top, lazy = _imports(name, outside)
        todo += [*top, *(m for m in lazy if not m.startswith(blocked))]
    return {name: module_file(name, outside) for name in seen}


def code_hash(path):
    """12 hex digits of a file's content; for Python, of its syntax tree without
    docstrings, comments and layout, so only a change of what executes changes it.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> (d / "a.py").write_text("'''Doc.'''\\nx = 1  # one\\n") and None
    >>> (d / "b.py").write_text("# other comment\\nx = (1)\\n") and None
    >>> code_hash(d / "a.py") == code_hash(d / "b.py")
    True
    """
    path = Path(path)
    stat = path.stat()
    return _hash(path, stat.st_mtime_ns, stat.st_size)


@cache
def _hash(path, mtime, size):
    data = path.read_bytes()
    if path.suffix == ".py":
        tree = ast.parse(data)
        for node in ast.walk(tree):
            body = getattr(node, "body", None)
            if (isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                  ast.AsyncFunctionDef)) and body
                    and isinstance(body[0], ast.Expr)
                    and isinstance(body[0].value, ast.Constant)
                    and isinstance(body[0].value.value, str)):
                node.body = body[1:] or [ast.Pass()]
        data = ast.dump(tree).encode()
    return hashlib.sha256(data).hexdigest()[:12]


def data_files():
    """The library's data files (built-in cases and meshes), sorted."""
    return sorted(p for p in PACKAGE.rglob("*") if p.suffix in DATA)


def dependencies(roots, solvers=SOLVERS):
    """``{path: code_hash}`` over the modules of :func:`closure` and the data files;
    paths relative to the package (absolute for a module outside it)."""
    files = [*closure(roots, solvers).values(), *data_files()]
    return {_name(p): code_hash(p) for p in sorted(set(files))}


def _name(path):
    """A file's key: its path relative to the package, or absolute outside it."""
    path = Path(path).resolve()
    return (path.relative_to(PACKAGE).as_posix() if path.is_relative_to(PACKAGE)
            else path.as_posix())


def digest(hashes):
    """16 hex digits over ``{path: hash}``."""
    text = "\n".join(f"{k} {v}" for k, v in sorted(hashes.items()))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def changed(hashes):
    """The paths of ``{path: hash}`` whose file today differs or is gone, sorted."""
    out = []
    for rel, old in hashes.items():
        path = PACKAGE / rel          # an absolute key stays itself
        if not path.is_file() or code_hash(path) != old:
            out.append(rel)
    return sorted(out)


def package_hash():
    """16 hex digits over every module and data file of the package: the source the
    report is assembled from."""
    files = sorted(PACKAGE.rglob("*.py")) + data_files()
    return digest({_name(p): code_hash(p) for p in files})
