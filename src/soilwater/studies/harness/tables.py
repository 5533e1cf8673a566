"""Tables of the report: each returns a pandas DataFrame and can write CSV and Markdown."""

import pandas as pd

from soilwater.material.presets import material_from_spec
from soilwater.studies.harness.runs import ERR_NOISE


def table1(preset="table1"):
    """The paper's Table 1, read from the material preset (so it shows what runs).

    Returns
    -------
    pandas.DataFrame
        Columns ``parameter, symbol, value``.
    """
    clay = material_from_spec({"preset": preset})
    rows = [
        ("Compression index", "lambda", clay.lam),
        ("Swelling index", "kappa", clay.kappa),
        ("Critical state parameter", "M", clay.M),
        ("Poisson's ratio", "nu", clay.nu),
        ("Initial void ratio", "e0", clay.e0),
        ("Initial volume ratio", "v0 = 1 + e0", clay.v0),
        ("Initial consolidation stress", "p'0", clay.p0),
    ]
    return pd.DataFrame(rows, columns=["parameter", "symbol", "value"])


def to_markdown(frame, floatfmt="{:.6g}"):
    """A GitHub Markdown table of ``frame`` (no extra dependency)."""
    def cell(x):
        if isinstance(x, float):
            return "-" if x != x else floatfmt.format(x)
        return str(x)

    lines = ["| " + " | ".join(map(str, frame.columns)) + " |",
             "|" + "---|" * len(frame.columns)]
    lines += ["| " + " | ".join(cell(x) for x in row) + " |"
              for row in frame.itertuples(index=False)]
    return "\n".join(lines) + "\n"


def write(frame, stem):
    """Write ``stem.csv`` and ``stem.md``; returns the two paths."""
    csv, md = stem.with_suffix(".csv"), stem.with_suffix(".md")
    frame.to_csv(csv, index=False)
    md.write_text(to_markdown(frame))
    return csv, md


#: ERR columns of the path summary and the bifurcation table whose values below the
#: Newton noise are written as a bound.
NOISY = ("err_before", "err_max", "err_final", "err_after_min", "err_after_max")


def below_noise(table, columns=NOISY, noise=ERR_NOISE):
    """The table with ERR values below ``noise`` written as a bound ``"< noise"``: their
    digits are the Newton tolerance's noise and differ between linear solvers."""
    bound = f"< {noise:g}"
    return table.assign(**{c: table[c].map(lambda v: bound if v < noise else v)
                           .astype(object) for c in columns if c in table})


def marked(table, columns):
    """The table with a † after the names of its branch-dependent ``columns``."""
    return table.rename(columns={c: f"{c} †" for c in columns})
