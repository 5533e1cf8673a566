"""The ``soilwater`` command: ``list``, ``show``, ``run``, ``path``, ``report``, ``check``,
``bench``.

Nothing fails with a traceback. Exit status:

* 2: an error the user can fix (bad input, a run that cannot converge, a refused
  ``--out``) or an operating-system error (disk full, permission, read-only file system);
  one line ``soilwater: error: ...`` on stderr; nothing is written.
* 130 (SIGINT, Ctrl-C) or 143 (SIGTERM): one line ``soilwater: interrupted (...)``;
  temporary files are removed, no half-written output is left.
* 141: standard output closed early (``soilwater show CASE | head -1``); silent, like a
  command killed by SIGPIPE.
"""

import multiprocessing
import os
import signal
import sys
import threading
from contextlib import contextmanager

from soilwater.arguments import MAX_POINTS, Parser, finite, ocr, points
from soilwater.errors import SoilwaterError

#: Exit status when standard output is closed early: 128 + SIGPIPE, as the shell reports.
BROKEN_PIPE = 141


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived; raised by the handler of :func:`interruptible` so the
    cleanup of every ``except BaseException`` on the way runs."""

    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


def main(argv=None):
    """Entry point of the console script; returns the exit status (see the module)."""
    with interruptible() as received:
        try:
            args = _parser().parse_args(argv)
            status = args.func(args) or 0
            sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
            return status
        except SoilwaterError as err:
            return _fail(f"error: {err}", 2)
        except KeyboardInterrupt as err:
            return _interrupted(getattr(err, "signum", signal.SIGINT))
        except MemoryError:
            return _fail("error: out of memory: this machine cannot hold the problem; "
                         "make it smaller (fewer nodes, sizes or steps)", 2)
        except BrokenPipeError:
            # the Python documentation's recipe: no second error at interpreter exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return BROKEN_PIPE
        except OSError as err:
            if received:
                return _interrupted(received[0])
            return _fail(f"error: {os_message(err)}", 2)
        except Exception:
            # a signal that landed inside a library callback (numba's compiler, through
            # ctypes) is swallowed there and resurfaces as that library's own error
            if received:
                return _interrupted(received[0])
            raise


def _interrupted(signum):
    return _fail(f"interrupted ({signal.Signals(signum).name}): no half-written output "
                 "was left", 128 + signum)


def _fail(message, status):
    print(f"soilwater: {message}", file=sys.stderr)
    return status


def os_message(err):
    """One line for an operating-system error: the path(s) it names, then the reason.

    >>> os_message(OSError(28, "No space left on device", "runs/a/fields_0000.vtu"))
    'runs/a/fields_0000.vtu: No space left on device'
    """
    paths = [str(name) for name in (err.filename, err.filename2) if name is not None]
    reason = err.strerror or str(err)
    return f"{' -> '.join(paths)}: {reason}" if paths else reason


@contextmanager
def interruptible():
    """While the block runs, SIGINT and SIGTERM raise :class:`Interrupted` in this process;
    the block gets the list of signals received so far.

    The handler first terminates this process's multiprocessing children (the workers of
    a sweep), so that waiting for them does not outlast the signal. A worker forked inside
    the block inherits the handler; there it restores the default action and re-sends the
    signal, so the worker ends quietly, without a traceback. A signal ignored on entry
    (SIGINT of a background job) stays ignored; the previous handlers are restored on exit.
    Where the signal lands inside a ctypes callback (numba compiling, through llvmlite),
    Python cannot raise it there: it is not reported as an unraisable exception but sent
    again 50 ms later, and a library error it caused meanwhile is turned into the
    interruption by :func:`main`.
    """
    pid, received = os.getpid(), []

    def handler(signum, frame):
        if os.getpid() != pid:
            signal.signal(signum, signal.SIG_DFL)
            os.kill(os.getpid(), signum)
        else:
            received.append(signum)
            for child in multiprocessing.active_children():
                child.terminate()
            raise Interrupted(signum)

    def unraisable(info):  # Interrupted inside a ctypes callback: sent again, once out
        if isinstance(info.exc_value, Interrupted):
            threading.Timer(0.05, resend, (info.exc_value.signum,)).start()
        else:
            default(info)

    def resend(signum):
        if active:
            os.kill(pid, signum)

    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)
                if signal.getsignal(s) is not signal.SIG_IGN}
    default, sys.unraisablehook = sys.unraisablehook, unraisable
    active = True
    try:
        yield received
    finally:
        active = False
        sys.unraisablehook = default
        for signum, action in previous.items():
            signal.signal(signum, action)


def _parser():
    from soilwater.methods import METHODS
    from soilwater.material.camclay import MAX_OCR
    from soilwater.material.driver import TESTS
    from soilwater.targets import MARKER

    parser = Parser(
        prog="soilwater",
        description="EFG and FEM side by side on soil-water coupled problems.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("list", help="list the built-in cases")
    p.set_defaults(func=_list)

    p = sub.add_parser("show", help="validate a case and print its resolved definition",
                       description="Load a built-in case or a TOML file, apply --set "
                       "overrides, validate everything and print the case as JSON.")
    _case_arguments(p)
    p.set_defaults(func=_show)

    p = sub.add_parser("run", help="run a case with a method and write its result folder",
                       description="Solve a case (built-in name or TOML file) and write "
                       "DIR/summary.json, DIR/history.csv and DIR/fields.pvd with VTU files. "
                       "DIR must be new, empty or a previous result (it holds "
                       f"{MARKER}) holding nothing else; it is replaced only when the run "
                       "succeeds, and a second run on DIR is refused while one writes it.")
    _case_arguments(p)
    p.add_argument("--method", required=True, choices=list(METHODS), help="solver")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="result folder: new, empty or a previous result")
    p.add_argument("--quiet", action="store_true", help="no progress (by default a bar "
                   "on a terminal, else a line every few steps on stderr: step, time, "
                   "Newton iterations, cut-backs, elapsed and estimated time left)")
    p.set_defaults(func=_run)

    p = sub.add_parser("path", help="stress-point driver: a material under a named test",
                       description="Integrate the rate equations of a material under a "
                       "prescribed velocity gradient (the paper's theoretical solution). "
                       "Tests: " + "; ".join(f"{k}: {v}" for k, v in TESTS.items()))
    p.add_argument("material", help="preset name (table1) or TOML file with [material]")
    p.add_argument("--test", required=True, choices=list(TESTS), metavar="NAME",
                   help="one of: " + ", ".join(TESTS))
    p.add_argument("--strain", required=True, type=finite,
                   help="final axial strain (shear strain for simple shear), positive")
    p.add_argument("--ocr", type=ocr, help="isotropic overconsolidation ratio p'c0/p'0, "
                   f"1 to {MAX_OCR:g}")
    p.add_argument("--model", choices=["original", "modified"], help="Cam-clay variant")
    p.add_argument("--points", type=points, default=200,
                   help=f"output rows, 1 to {MAX_POINTS} (default 200)")
    p.add_argument("--out", required=True, help="CSV file: step, eps_a, eps_v, p, q, pc")
    p.set_defaults(func=_path)

    p = sub.add_parser("infsup", help="numerical inf-sup test of element pairs and EFG "
                       "weight settings on a unit square",
                       description="The Chapelle-Bathe inf-sup test on n x n grid nodes "
                       "of a unit square, with each method's own shape functions and "
                       "quadrature; writes FILE.csv and a log-log figure FILE.png of "
                       "beta against h with the slope of each pair.")
    p.add_argument("--methods", default="fem-th,fem-p1p1,efg",
                   help="comma-separated: efg and FEM pairs (default fem-th,fem-p1p1,efg)")
    p.add_argument("--sizes", default="5,9,17,33",
                   help="comma-separated nodes per side, >= 3 (default 5,9,17,33)")
    p.add_argument("--boundary", choices=["free", "dirichlet"],
                   help="displacement boundary: free, or v = 0 (default: both)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="EFG settings, e.g. efg.weight_u=exp:0.5 (repeatable)")
    p.add_argument("--out", required=True, metavar="FILE.csv", help="CSV table")
    p.set_defaults(func=_infsup)

    p = sub.add_parser("check", help="rerun the fast subset and compare with "
                       "reports/reference/ (exit 1 on a regression)")
    p.add_argument("--update", action="store_true",
                   help="rewrite the reference tables instead (commit them deliberately)")
    p.set_defaults(func=_check)

    p = sub.add_parser("bench", help="speed ratios against scikit-fem (writes "
                       "reports/bench.md)")
    p.add_argument("--out", default="reports/bench.md", help="Markdown table")
    p.add_argument("--sizes", help="comma-separated node counts, e.g. 1000,3e5 (default "
                   "soilwater.studies.bench.plan.SIZES)")
    p.set_defaults(func=_bench)

    p = sub.add_parser("report", help="regenerate every figure and table under reports/")
    p.add_argument("--out", help="report folder (default reports; reports-quick with "
                   "--quick)")
    p.add_argument("--quick", action="store_true", help="every study at a coarser "
                   "resolution, a first look in about 15 minutes, labelled quick, into its "
                   "own folder")
    p.add_argument("--redraw", action="store_true", help="run nothing: redraw the figures "
                   "from the studies' saved outputs and rebuild REPORT.md")
    p.add_argument("--only", metavar="STUDY[,STUDY]", help="rerun only these studies and "
                   "rebuild REPORT.md from every study's last saved output")
    p.add_argument("--dask", metavar="ADDRESS", help="send the sweeps to a Dask "
                   "distributed scheduler (pip install 'soilwater[dask]')")
    p.add_argument("--cache", metavar="DIR", help="keep the finished runs in DIR "
                   "(default: $SOILWATER_CACHE, else .cache/runs in the checkout)")
    p.set_defaults(func=_report)
    return parser


def _case_arguments(p):
    """The case and its ``--set`` overrides, shared by ``show`` and ``run``."""
    p.add_argument("case", help="built-in case name or TOML file")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case entry, e.g. material.permeability=1e-6 or "
                   "efg.cells=squares (repeatable)")


def _list(args):
    from soilwater.case.loader import builtin_cases

    cases = builtin_cases()
    width = max(map(len, cases))
    for name, case in cases.items():
        print(f"{name:<{width}}  {case.description}")


def _show(args):
    import json

    from soilwater.case.loader import load_case

    from soilwater.efg.settings import configuration, departures

    case = load_case(args.case, args.set)
    print(json.dumps(case.to_dict(), indent=2))
    print(f"# {len(case.nodes())} nodes, {len(case.times()) - 1} time steps")
    name = configuration(case.efg)
    changed = "" if name != "custom" else ": " + ", ".join(departures(case.efg))
    print(f"# method efg runs the {name} EFG configuration{changed}; method efg-paper "
          "the paper's")


def _run(args):
    from soilwater.case.loader import load_case
    from soilwater.methods import solve
    from soilwater.locks import claim

    with claim(args.out, what="--out"):  # before any work; held until written
        case = load_case(args.case, args.set)
        result = solve(case, args.method, progress=not args.quiet)
        result.write(args.out, what="--out")
    print(f"wrote {args.out}: {json_line(result.summary)}")


def json_line(summary):
    """A short one-line digest of a run summary for the terminal."""
    errors = summary.get("errors", {})
    text = ", ".join(f"{k} error {v:.3g}" for k, v in errors.items())
    stopped = summary.get("stopped")
    return f"{summary.get('steps')} step(s), {summary.get('dofs')} dofs" + (
        f", {text}" if text else "") + (f"; stopped early {stopped}" if stopped else "")


def _path(args):
    from soilwater.material.driver import PATH_COLUMNS, run_test
    from soilwater.material.presets import load_material
    from soilwater.targets import check_output_file, write_csv

    check_output_file(args.out, PATH_COLUMNS)  # before any work
    material = load_material(args.material, model=args.model, ocr=args.ocr)
    if not material.plastic:
        raise SoilwaterError(f"material {args.material!r} is elastic: the driver runs "
                             "Cam-clay (model = original or modified)")
    table = run_test(material, args.test, args.strain, points=args.points)
    write_csv(table, args.out)
    print(f"wrote {args.out} ({len(table)} rows)")


def _infsup(args):
    from soilwater.diagnostics.pairs import BOUNDARIES, write

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    try:
        sizes = [int(n) for n in args.sizes.split(",")]
    except ValueError:
        raise SoilwaterError(f"--sizes {args.sizes!r}: give comma-separated integers, "
                             "e.g. 5,9,17,33") from None
    if not methods:
        raise SoilwaterError(f"--methods {args.methods!r}: give one or more methods, "
                             "e.g. fem-th,fem-p1p1,efg")
    for option, values in (("--methods", methods), ("--sizes", sizes)):
        twice = sorted({str(v) for v in values if values.count(v) > 1})
        if twice:
            raise SoilwaterError(f"{option} names {', '.join(twice)} twice: give each once")
    others = [s for s in args.set if not s.strip().startswith("efg.")]
    if others:
        raise SoilwaterError(f"--set {others[0]!r}: infsup takes EFG settings only "
                             "(efg.KEY=VALUE, e.g. efg.weight_u=exp:0.5)")
    boundaries = [args.boundary] if args.boundary else list(BOUNDARIES)
    for path in write(args.out, methods, sizes, boundaries, args.set):
        print(f"wrote {path}")


def _check(args):
    from soilwater.studies.check import check, update

    if args.update:
        for path in update():
            print(f"wrote {path}")
        return 0
    failures = 0
    for name, lines in check().items():
        print(f"{name}: {'ok' if not lines else f'{len(lines)} difference(s)'}")
        for line in lines:
            print(f"  {line}")
        failures += len(lines)
    return 1 if failures else 0


def _bench(args):
    from soilwater.studies.bench.plan import SIZES, parse_sizes
    from soilwater.studies.bench.study import run

    run(args.out, sizes=SIZES if args.sizes is None else parse_sizes(args.sizes))


def _report(args):
    if args.quick:                      # before any study is imported: it picks its sizes
        os.environ["SOILWATER_QUICK"] = "1"
    from soilwater.studies.harness import runner
    from soilwater.studies.report import QUICK_FOLDER, make_report

    runner.DASK["address"] = args.dask
    if args.cache:
        os.environ["SOILWATER_CACHE"] = args.cache
    out = args.out or (QUICK_FOLDER if args.quick else "reports")
    for path in make_report(out, only=args.only, redraw=args.redraw, what="--out"):
        print(f"wrote {path}")


def entry():
    """The console script: :func:`main`, then exit. After an interruption the process ends
    at once (``os._exit``, streams flushed): a signal that landed inside numba's compiler
    can leave LLVM objects whose finalisers crash the interpreter's shutdown."""
    status = main()
    if status in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    sys.exit(status)


if __name__ == "__main__":
    entry()
