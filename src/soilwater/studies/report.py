"""``soilwater report``: run the studies of :mod:`soilwater.studies.registry` (all, or
those of ``--only``) and assemble ``reports/REPORT.md`` from every study's last output.

Each study writes its tables under ``root/tables`` and figures under ``root/figures``
and saves the numbers of its section under ``root/studies``
(:mod:`soilwater.studies.harness.study`). REPORT.md states under each section the
code it was made from and marks it stale when the sources it depends on have changed
since; a study never run says so in place of its section.
"""

import os
import sys
from pathlib import Path

from tqdm import tqdm

from soilwater.errors import SoilwaterError
from soilwater.nonlinear.progress import _isatty, clock
from soilwater.studies import registry, verdicts
from soilwater.studies.harness import quick as _quick
from soilwater.studies.harness import runner
from soilwater.studies.harness import study as store


#: The folder of ``soilwater report --quick`` by default (never ``reports/``).
QUICK_FOLDER = "reports-quick"


def select(only):
    """The names of the studies to run, in report order: all for None, else those of
    ``only`` (``"NAME[,NAME]"``).

    Raises
    ------
    SoilwaterError
        For a name that is not a study, in one line listing the studies.
    """
    if only is None:
        return list(registry.STUDIES)
    names = [n.strip() for n in only.split(",") if n.strip()]
    unknown = [n for n in names if n not in registry.STUDIES]
    if unknown or not names:
        raise SoilwaterError(f"--only {only!r}: unknown study {', '.join(unknown) or '(none)'}"
                             f"; use one or more of {', '.join(registry.STUDIES)}")
    return [name for name in registry.STUDIES if name in names]


def make_report(root="reports", only=None, redraw=False):
    """Run the studies (all, or ``only``: ``"NAME[,NAME]"``) into ``root`` and write
    ``root/REPORT.md`` from every study's last saved output; returns the paths of the
    saved outputs and REPORT.md.

    Parameters
    ----------
    root : path
        The report's folder.
    only : str, optional
        ``"NAME[,NAME]"``: run these studies only.
    redraw : bool
        Run no study: redraw the figures of the selected studies from their saved outputs
        (those whose report module has ``figures(root, data)``) and rebuild REPORT.md.

    Raises
    ------
    SoilwaterError
        For an unknown study, a study whose needed study has no saved output, or a folder
        holding the other resolution's report.

    Notes
    -----
    In a process started with ``SOILWATER_QUICK=1`` (``soilwater report --quick``)
    every study is made at its quick resolution (:mod:`soilwater.studies.harness.quick`)
    and each page and figure is labelled so; ``root`` must then not hold a full report,
    nor a full report's ``root`` a quick one.
    """
    import matplotlib

    matplotlib.use("Agg")               # the studies write PNGs, never show them
    root = Path(root)
    names = select(only)
    for sub in ("tables", "figures"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    studies = registry.STUDIES
    quick = _quick.active()
    settings = {"linear_solver": _linear_solver(), "dask": runner.DASK["address"],
                "cores": os.cpu_count(), "quick": quick}
    saved = {name: store.load(root, name) for name in studies}
    _same_resolution(root, saved, quick)
    if redraw:
        names = [n for n in names if saved[n] is not None
                 and callable(getattr(studies[n].load(), "figures", None))]
        for name in names:
            studies[name].load().figures(root, saved[name].data)
        names = []
    plan = Plan(names, saved)
    for name in names:
        plan.start(name)
        study = studies[name]
        missing = [n for n in study.needs if saved[n] is None]
        if missing:
            raise SoilwaterError(f"study {name} reads the output of {', '.join(missing)}: "
                                 f"run soilwater report --only {','.join(missing)},{name}")
        saved[name] = store.run(study, root, {n: saved[n].data for n in study.needs},
                                studies, settings)
    plan.close()
    text = markdown(saved, {name: store.inputs_hash(s, studies, store.solvers(saved[name]))
                            for name, s in studies.items() if saved[name] is not None},
                    quick)
    (root / "REPORT.md").write_text(text)
    return [p for name in names for p in store.paths(root, name)] + [root / "REPORT.md"]


def _same_resolution(root, saved, quick):
    """Refuse a folder holding saved studies of the other resolution (a quick report
    never writes over a full one, nor the reverse)."""
    other = [n for n, s in saved.items()
             if s is not None and bool(s.meta["settings"].get("quick")) != bool(quick)]
    if other:
        held, flag = ("a full", "--quick") if quick else ("a quick", "")
        raise SoilwaterError(
            f"{root} holds {held} report ({', '.join(other)}): write "
            + (f"the quick one elsewhere ({flag} --out DIR; default {QUICK_FOLDER})"
               if quick else "the full one elsewhere (--out DIR; default reports)"))


class Plan:
    """The report's progress over its studies: which is being made and the time left by
    each study's last recorded wall time (a terminal gets a bar, anything else a line per
    study)."""

    def __init__(self, names, saved):
        self.names, self.done = list(names), 0
        self.seconds = {n: saved[n].meta["seconds"] if saved[n] is not None else None
                        for n in names}
        self.bar = tqdm(total=len(names), desc="report", unit="study",
                        disable=not _isatty(sys.stderr) or None) if names else None

    def start(self, name):
        """Study ``name`` begins."""
        runner.PROGRESS.update(show=True, desc=name)
        left = [self.seconds[n] for n in self.names[self.done:]]
        known = sum(s for s in left if s is not None)
        unknown = sum(s is None for s in left)
        eta = (f"about {clock(known)} left by their last runs"
               if unknown < len(left) else "")
        eta += (f"{' + ' if eta else ''}{unknown} {'study' if unknown == 1 else 'studies'} never made here" if unknown else "")
        self.done += 1
        if self.bar is None or self.bar.disable:
            print(f"report: study {self.done}/{len(self.names)} {name}; {eta}",
                  file=sys.stderr, flush=True)
        else:
            self.bar.set_postfix_str(f"{name}; {eta}")
            self.bar.update(0 if self.done == 1 else 1)

    def close(self):
        runner.PROGRESS.update(show=False, desc="sweep")
        if self.bar is not None:
            self.bar.update(1)
            self.bar.close()


def _linear_solver():
    from soilwater.linalg.backends import identity

    return identity()


def provenance(name, saved, today):
    """The line under a section: the code it was made from, or **stale** when ``today``'s
    source hash differs from the recorded one."""
    meta = saved.meta
    if meta["code"] != today:
        return (f"**Stale**: section `{name}` was made from code `{meta['code'][:7]}` on "
                f"{meta['made']}; the sources it depends on have changed since "
                f"(`{today[:7]}`): rerun `soilwater report --only {name}`.")
    solvers = ", ".join(f"`{s}/`" for s in meta.get("solvers", ())) or "no solver"
    return (f"*Section `{name}`: made from code `{meta['code'][:7]}` (shared library, "
            f"{solvers}, its study) on {meta['made']} in {meta['seconds']:.0f} s.*")


def markdown(saved, hashes, quick=False):
    """REPORT.md from the saved outputs (name -> :class:`~soilwater.studies.harness.
    study.Saved` or None) and today's source hashes of the saved ones (name -> hash over
    the solvers each used); ``quick``: a quick report's, labelled so at its top and under
    each section."""
    lines = _header(saved, quick)
    if quick:
        lines[1:1] = ["", f"**{_quick.LABEL}.** Its numbers come from coarser runs than "
                      "the full report states: read them as a first look, not as the "
                      "report's findings."]
    for name, study in registry.STUDIES.items():
        if saved[name] is None:
            lines += [f"## {name}", "", f"*Study `{name}` has not been run yet: "
                      f"`soilwater report --only {name}`.*", ""]
            continue
        fresh = saved[name].meta["code"] == hashes[name]
        lines += [*_readable(lambda: study.load().section(saved[name].data), fresh,
                             f"## {name}", f"section `{name}`", name),
                  provenance(name, saved[name], hashes[name]), ""]
        if quick:
            lines[-1:-1] = [f"*{_quick.LABEL}.*"]
    stale = [n for n in verdicts.NEEDS
             if saved.get(n) is not None and saved[n].meta["code"] != hashes[n]]
    lines += _readable(
        lambda: verdicts.section({n: s.data for n, s in saved.items() if s is not None}),
        not stale, "## Verdicts on the paper's claims", "the verdicts", ",".join(stale))
    if stale:
        lines += [f"**Stale**: the verdicts read sections made from older code "
                  f"({', '.join(stale)}).", ""]
    return "\n".join(lines + DIFFERENCES)


def _readable(render, fresh, title, what, rerun):
    """``render()``'s lines; for output saved by older code that today's cannot read (a
    table without a column it now needs), a title and one line asking for the rerun in
    place of a traceback. Output of today's code is always rendered (its errors raise)."""
    if fresh:
        return render()
    try:
        return render()
    except (KeyError, IndexError, ValueError, AttributeError, TypeError):
        return [title, "", f"*{what.capitalize()} cannot be written from output saved by "
                f"older code: rerun `soilwater report --only {rerun}`.*", ""]


def _header(saved, quick):
    """The report's title and how it was made: wall time and cached runs summed over the
    saved studies, on the cores their runs recorded."""
    made = [s.meta for s in saved.values() if s is not None]
    seconds = sum(m["seconds"] for m in made)
    runs, cached = sum(m["runs"] for m in made), sum(m["cached"] for m in made)
    cores = "/".join(str(c) for c in sorted({m["settings"]["cores"] for m in made})) or str(
        os.cpu_count())
    footing = saved.get("footing")
    cost = ("; from an empty cache the report takes far longer: the strip-footing "
            f"study's {len(footing.data['footing'])} runs alone take "
            f"{footing.data['footing'].run_time.sum() / 3600:.1f} h of run time, shared by "
            f"the {cores} cores" if footing is not None and not quick else "")
    return [
        "# soilwater report" + (" (quick)" if quick else ""),
        "",
        f"Regenerated by `make report{'-quick' if quick else ''}` (one study: `soilwater "
        f"report --only NAME`), its sections in {seconds:.0f} s on this machine ({cores} "
        f"cores) when last run, {cached} of {runs} solver runs read from the run cache "
        "(keyed by case, method, linear solver and solver source, so only what changed is "
        f"recomputed{cost}). Every number below comes from the run stated under its "
        "section; tables are under `tables/`, figures under `figures/`.",
        "",
    ]


#: The closing section: where this work departs from the paper.
DIFFERENCES = [
    "## Where we differ from the paper",
    "",
    "- The 111-node specimen is reconstructed (7 x 9 grid + cell centres): the "
    "paper's figure is not in our text.",
    "- EFG uses variationally consistent test gradients by default; the paper's plain "
    "Gauss quadrature is reported beside it (`efg.correction = \"none\"`).",
    "- The Table 2 ratings follow thresholds on a measured index, calibrated so that "
    "Taylor-Hood rates good and P1/P1 at k = 0 bad; the paper gives no numbers. Our "
    "sweep does not reproduce its 'good' for E-A/E-B at high density.",
    "",
]
