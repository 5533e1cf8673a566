"""``soilwater report``: regenerate every figure and table under ``reports/``."""

from pathlib import Path

from tqdm import tqdm

from comparisons import figures, peers, tables, verification


def make_report(root="reports"):
    """Write the report files; returns the list of paths written.

    Tables go to ``root/tables``, figures to ``root/figures``.
    """
    root = Path(root)
    (root / "tables").mkdir(parents=True, exist_ok=True)
    (root / "figures").mkdir(parents=True, exist_ok=True)
    tasks = [
        ("Table 1", lambda: tables.write(tables.table1(), root / "tables" / "table1")),
        ("peer single-point data",
         lambda: tables.write(peers.summary(), root / "tables" / "peer_single_point")),
        ("shape functions (Fig. 7)",
         lambda: [figures.shape_functions(root / "figures" / "shape_functions.png")]),
        ("background cells (Figs. 3, 5)",
         lambda: [figures.background_cells(root / "figures" / "cells.png")]),
        ("patch test", lambda: tables.write(verification.patch_test(),
                                            root / "tables" / "patch_test")),
        ("cantilever convergence", lambda: _convergence(root)),
        ("stress paths (Figs. 4, 6)", lambda: _paths(root)),
        ("soil column stability (Table 2, EFG)",
         lambda: tables.write(verification.soil_column(), root / "tables" / "table2_efg")),
        ("Terzaghi and Mandel (EFG)",
         lambda: tables.write(verification.consolidation(),
                              root / "tables" / "efg_consolidation")),
        ("FEM Terzaghi (vs MOOSE and closed form)",
         lambda: tables.write(verification.fem_terzaghi(moose=peers.moose_terzaghi()),
                              root / "tables" / "fem_terzaghi")),
        ("FEM soil column stability",
         lambda: tables.write(verification.fem_soil_column(),
                              root / "tables" / "fem_soil_column")),
        ("soil column profiles (Fig. 8 analogue)", lambda: _column(root)),
        ("Terzaghi and Mandel, EFG and FEM", lambda: _consolidation(root)),
        ("stress paths (driver)",
         lambda: [figures.stress_paths_driver(root / "figures" / "stress_paths_driver.png")]),
    ]
    written = []
    for name, task in (bar := tqdm(tasks, desc="report", unit="item")):
        bar.set_postfix_str(name)
        written += list(task())
    return written


def _convergence(root):
    table = verification.cantilever_convergence(corrections=("vci", "none"))
    vci = table[table.correction == "vci"]
    return [*tables.write(table, root / "tables" / "efg_convergence"),
            figures.efg_convergence(vci, root / "figures" / "efg_convergence.png")]


def _paths(root):
    table = verification.stress_paths()
    return [*tables.write(table, root / "tables" / "stress_paths"),
            *tables.write(verification.path_summary(table),
                          root / "tables" / "stress_paths_summary"),
            figures.stress_paths(table, root / "figures" / "fig4_stress_paths.png"),
            figures.err_history(table, root / "figures" / "fig6_err.png")]


def _column(root):
    table = verification.column_profiles()
    return [*tables.write(table, root / "tables" / "column_profiles"),
            figures.column_profiles(table, root / "figures" / "column_profiles.png")]


def _consolidation(root):
    terzaghi, mandel = verification.consolidation_histories()
    return [*tables.write(mandel, root / "tables" / "mandel_centre"),
            figures.consolidation(terzaghi, mandel, root / "figures" / "consolidation.png")]
