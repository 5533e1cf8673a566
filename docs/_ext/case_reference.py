"""The ``case-schema`` directive: the case reference, read from the schema at build time.

:mod:`soilwater.case.schema` documents every key of a case in its module docstring, as an
annotated TOML file (value, then unit, default and bounds in the comment), and holds the
keys each section accepts (``KEYS``) and the load-time bounds as constants;
the readers of :mod:`soilwater.case` hold the choices of each string key, in their
``string(table, key, section, default, choices)`` calls. The directive turns these into
one table per section, a table of the bounds and the schema's prose, so the page changes
whenever the schema does.
"""

import ast
import importlib
import inspect
import pkgutil
import re
from pathlib import Path

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.pycode import ModuleAnalyzer
from sphinx.util.docutils import SphinxDirective

from soilwater import case
from soilwater.case import schema

_KEY = re.compile(r"^(#\s*)?([A-Za-z_][\w-]*)\s*=\s*(.*?)\s*(?:#\s?(.*))?$")
_SECTION = re.compile(r"^\[([\w.-]+)\]\s*(?:#\s?(.*))?$")


def schema_block(doc):
    """Split the schema docstring into (prose before, annotated TOML lines, prose after)."""
    lines = inspect.cleandoc(doc).splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Schema")
                 and line.rstrip().endswith("::"))
    end = next((i for i in range(start + 2, len(lines))
                if lines[i] and not lines[i].startswith(" ")), len(lines))
    block = [line[4:] for line in lines[start + 1:end]]
    return lines[:start], block, lines[end:]


def _accepted(section):
    """The keys ``schema.KEYS`` lists for ``section`` (None: not listed there)."""
    if section.startswith("boundary."):
        return schema.KEYS["segment" if section.count(".") == 2 else "edge"]
    return schema.KEYS.get(section)


def sections(block):
    """``[(section, note, [[key, example, alternative, note]])]`` of the annotated TOML.

    A comment line under a key continues that key's note; a commented-out key (one the
    section accepts) is an alternative to the key above it.
    """
    table = [("(top level)", "", [])]
    for line in block:
        text = line.strip()
        if not text:
            continue
        if match := _SECTION.match(text):
            table.append((match[1], match[2] or "", []))
            continue
        match = _KEY.match(text)
        accepted = _accepted(table[-1][0])
        if match and (match[1] is None or accepted is None or match[2] in accepted):
            table[-1][2].append([match[2], match[3], bool(match[1]), match[4] or ""])
            continue
        note = text.lstrip("#").strip()
        rows = table[-1][2]
        if rows:
            rows[-1][3] = f"{rows[-1][3]} {note}".strip()
        else:
            table[-1] = (table[-1][0], f"{table[-1][1]} {note}".strip(), rows)
    return table


def _resolve(node, module):
    """The value of a choices argument: a literal, a name or ``NAME[key]`` of ``module``."""
    try:
        return ast.literal_eval(node)
    except ValueError:
        pass
    if isinstance(node, ast.Name):
        return getattr(module, node.id, None)
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
        table = getattr(module, node.value.id, {})
        key = getattr(node.slice, "value", None)
        return table.get(key) if isinstance(table, dict) else None
    return None


def choices():
    """``{(section, key): choices}`` from the string readers of ``soilwater.case``.

    Every call ``string(table, "key", "section", default, choices)`` in the modules of
    the package; where ``section`` is no literal (the edges and the segments), the name
    of the function that makes the call stands for it.
    """
    found = {}
    for info in pkgutil.iter_modules(case.__path__):
        module = importlib.import_module(f"{case.__name__}.{info.name}")
        tree = ast.parse(inspect.getsource(module))
        caller = {id(node): function.name for function in ast.walk(tree)
                  if isinstance(function, ast.FunctionDef) for node in ast.walk(function)}
        for call in ast.walk(tree):
            if not (isinstance(call, ast.Call)
                    and getattr(call.func, "id", "") == "string"
                    and len(call.args) >= 3 and isinstance(call.args[1], ast.Constant)):
                continue
            options = call.args[4] if len(call.args) >= 5 else next(
                (k.value for k in call.keywords if k.arg == "choices"), None)
            value = None if options is None else _resolve(options, module)
            if isinstance(value, (tuple, list, frozenset, set)):
                where = (call.args[2].value if isinstance(call.args[2], ast.Constant)
                         else caller.get(id(call)))
                found[(where, call.args[1].value)] = tuple(value)
    if not found:
        raise RuntimeError("case reference: no string(table, key, section, default, "
                           "choices) call found in soilwater.case: update "
                           "docs/_ext/case_reference.py to the readers' new name")
    return found


def _cell(text):
    """``text`` for a table cell: its bars escaped (RST reads ``|x|`` as a substitution)."""
    return text.replace("|", r"\|") if text else ""


def _code(text):
    """``text`` as an inline literal (empty stays empty)."""
    return f"``{text}``" if text else ""


def section_table(name, note, rows, options):
    """RST lines of one section: its note and a list-table of its keys."""
    title = name if name == "(top level)" else f"[{name}]"
    lines = [title, "-" * len(title), ""]
    if note:
        lines += [_cell(note), ""]
    schema_name = {"(top level)": None}.get(name, name.split(".")[0])
    known = {row[0] for row in rows}
    accepted = _accepted(name) or ()
    extra = [key for key in accepted if key not in known]
    lines += [".. list-table::", "   :header-rows: 1", "   :widths: 18 22 20 40", "",
              "   * - key", "     - example", "     - choices", "     - unit, default, bounds"]
    for key, example, alternative, text in rows:
        option = options.get(("case" if schema_name is None else schema_name, key))
        if name.startswith("boundary."):
            kind = "segment" if name.count(".") == 2 else "edge"
            option = next((value for (where, k), value in options.items()
                           if k == key and where and kind in where), None)
        note = ("optional, commented out in the schema: " if alternative else "") + text
        lines += [f"   * - ``{key}``", f"     - {_code(example)}",
                  f"     - {', '.join(_code(o) for o in option) if option else ''}",
                  f"     - {_cell(note)}"]
    for key in extra:
        lines += [f"   * - ``{key}``", "     - ", "     - ", "     - see the notes below"]
    return lines + [""]


def bounds_table():
    """RST lines of the schema's numeric constants with their docstrings."""
    docs = ModuleAnalyzer.for_module(schema.__name__).find_attr_docs()
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 25 20 55", "",
             "   * - constant", "     - value", "     - meaning"]
    for (_, name), doc in docs.items():
        value = getattr(schema, name)
        if isinstance(value, (int, float)) or (isinstance(value, tuple) and value
                                              and all(isinstance(v, (int, float))
                                                      for v in value)):
            text = " ".join(line.strip() for line in doc if line.strip())
            lines += [f"   * - :data:`~soilwater.case.schema.{name}`", f"     - ``{value!r}``",
                      f"     - {text}"]
    return lines + [""]


def reference():
    """The whole case reference as RST lines."""
    before, block, after = schema_block(schema.__doc__)
    options = choices()
    lines = before[2:] + [""] if len(before) > 2 else []
    for name, note, rows in sections(block):
        lines += section_table(name, note, rows, options)
    lines += ["Bounds", "------", "", *bounds_table(), "Notes", "-----", "", *after, ""]
    return lines


class CaseSchema(SphinxDirective):
    """``.. case-schema::``: every section and key of a case, from the schema."""

    def run(self):
        for info in pkgutil.iter_modules(case.__path__):
            self.env.note_dependency(str(Path(case.__path__[0]) / f"{info.name}.py"))
        container = nodes.container()
        self.state.nested_parse(StringList(reference(), "case_reference"), 0, container,
                                match_titles=True)
        return container.children


def setup(app):
    app.add_directive("case-schema", CaseSchema)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}
