"""How far the strip footing gets with EFG's penalty and with Nitsche's method
(``efg.essential``), and how close to fem-th: the footing study's runs on two densities.

``python -m soilwater.studies.footing.reach`` prints the table (5 min on 2 cores).
"""

import pandas as pd

from soilwater.case.loader import load_case
from soilwater.studies.footing import study as footing
from soilwater.studies.harness.grids import refined

#: EFG's ways of imposing the essential conditions (``efg.essential``).
ESSENTIAL = ("penalty", "nitsche")


def footing_reach(methods=ESSENTIAL, densities=(4, 8)):
    """The strip-footing study's runs (:mod:`soilwater.studies.footing.study`, to 0.5 B in
    100 steps) with either method and with fem-th, on ``densities`` spacings per B at the footing:
    how far each gets and how far its curve lies from fem-th's on the finest.

    Returns
    -------
    pandas.DataFrame
        :func:`soilwater.studies.footing.study.summary`'s ``label, nodes, reached``, the
        pressure at :data:`soilwater.studies.footing.study.AT` B, ``error`` (against fem-th
        on ``densities[-1]``) and ``run_time``.
    """
    steps = load_case(footing.CASE).time.steps
    variants = [(f"efg, {m}", "efg", (f"efg.essential={m}",)) for m in methods]
    study = [(label, method, core, steps, (*refined(core), *extra))
             for core in densities
             for label, method, extra in (*variants, ("fem-th", "fem-th", ()))]
    table = footing.summary(footing.curves(study), reference=("fem-th", densities[-1]))
    return table[["label", "nodes", "reached", f"at_{footing.AT:g}B", "error", "run_time"]]


def main():
    """Print the table."""
    pd.set_option("display.width", 200)
    print("## Strip footing to 0.5 B: reach and error against fem-th\n")
    print(footing_reach().to_string(index=False, float_format="{:.3g}".format))


if __name__ == "__main__":
    main()
