"""The machine a study runs on: CPU, memory, NumPy's BLAS and its dense product rate.

:func:`cpu` and :func:`ram_gb` name the hardware; :func:`numpy_blas` reads the loaded
OpenBLAS through ctypes (its kernel and threads); :func:`dgemm` measures the rate of
``C = A B`` [GF/s = 10^9 flop/s] through NumPy and through MKL's ``cblas_dgemm``, the
yardstick of a factorisation's rate.
"""

import ctypes
import os
import platform
import time

import numpy as np

from soilwater.linalg.backends import available

#: Order of the dgemm of :func:`dgemm` (3 x 72 MB of matrices, about a second).
DGEMM_N = 3000
#: OpenBLAS reads these when it loads and picks its kernels and blocking from them;
#: ``make bench`` runs with both unset (``env -u``), so NumPy's BLAS uses the kernels of
#: this CPU. :func:`numpy_blas` records what the run saw.
OPENBLAS_VARIABLES = ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE")


def cpu():
    """The CPU model (``model name`` of /proc/cpuinfo, else what platform knows)."""
    try:
        with open("/proc/cpuinfo") as fh:
            return next(line.split(":", 1)[1].strip() for line in fh
                        if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def ram_gb():
    """This machine's physical memory [GB = 10^9 bytes]."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9


def best_of(fn, repeat=3):
    """Best wall time [s] of ``repeat`` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        tic = time.perf_counter()
        fn()
        times.append(time.perf_counter() - tic)
    return min(times)


def numpy_blas():
    """One line naming NumPy's BLAS: build name and version, and, read from the loaded
    OpenBLAS, its kernel (core) and threads, with the ``OPENBLAS_*`` variables it read."""
    blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
    text = f"{blas.get('name', 'unknown')} {blas.get('version', '')}".strip()
    library = _loaded("openblas")
    if library is not None:
        core = _call(library, ("scipy_openblas_get_corename64_", "openblas_get_corename64_",
                               "openblas_get_corename"), ctypes.c_char_p)
        threads = _call(library, ("scipy_openblas_get_num_threads64_",
                                  "openblas_get_num_threads64_", "openblas_get_num_threads"),
                        ctypes.c_int)
        text += f", core {core.decode() if core else 'unknown'}, {threads} threads"
    return text + "; " + ", ".join(f"{name} {os.environ.get(name, 'unset')}"
                                   for name in OPENBLAS_VARIABLES)


def _loaded(word, prefer="numpy"):
    """Path of a shared library loaded in this process whose file name has ``word``, one
    whose path has ``prefer`` first (SciPy loads an OpenBLAS of its own); None if none."""
    try:
        with open("/proc/self/maps") as fh:
            paths = [line.split()[-1] for line in fh]
    except OSError:
        return None
    paths = [path for path in paths if word in os.path.basename(path).lower()]
    return next((path for path in paths if prefer in path), paths[0] if paths else None)


def _call(path, names, restype):
    """The first function of ``names`` that the library ``path`` exports, called without
    arguments; None if it exports none."""
    library = ctypes.CDLL(path)
    for name in names:
        function = getattr(library, name, None)
        if function is not None:
            function.restype = restype
            return function()
    return None


def dgemm(n=DGEMM_N, repeat=3):
    """The machine's dense matrix product rate, the yardstick of the factorisation's.

    ``C = A B`` of two ``n x n`` float64 matrices, best of ``repeat`` after a warm-up,
    through NumPy's BLAS and through MKL's ``cblas_dgemm`` (the library PARDISO runs on,
    where ``pypardiso`` is installed), on all the threads each library uses.

    Returns
    -------
    dict
        ``n``; ``numpy_gflops`` and ``mkl_gflops``: ``2 n^3 / t`` [GF/s = 10^9 flop/s]
        (NaN without MKL); ``numpy_blas`` (:func:`numpy_blas`) and ``mkl`` (version and
        threads).

    Examples
    --------
    >>> rates = dgemm(200, repeat=1)
    >>> bool(rates["numpy_gflops"] > 0)
    True
    """
    rng = np.random.default_rng(0)
    a, b = rng.random((n, n)), rng.random((n, n))
    rates = {"n": n, "numpy_gflops": 2.0 * n**3 / best_of(lambda: a @ b, repeat) / 1e9,
             "numpy_blas": numpy_blas(), "mkl_gflops": np.nan, "mkl": "not installed"}
    if available("pardiso"):
        import pypardiso

        mkl = pypardiso.PyPardisoSolver().libmkl            # the library PARDISO calls
        c, double = np.empty((n, n)), ctypes.POINTER(ctypes.c_double)
        row_major, no_transpose = 101, 111                   # CBLAS enumerations

        def product():
            mkl.cblas_dgemm(row_major, no_transpose, no_transpose, n, n, n,
                            ctypes.c_double(1.0), a.ctypes.data_as(double), n,
                            b.ctypes.data_as(double), n, ctypes.c_double(0.0),
                            c.ctypes.data_as(double), n)

        rates["mkl_gflops"] = 2.0 * n**3 / best_of(product, repeat) / 1e9
        if not np.allclose(c[:, :4], a @ b[:, :4]):
            raise RuntimeError("MKL's dgemm through ctypes gave a wrong product")
        version = ctypes.create_string_buffer(256)
        mkl.MKL_Get_Version_String(version, len(version))
        mkl.MKL_Get_Max_Threads.restype = ctypes.c_int
        rates["mkl"] = f"{version.value.decode()}, {mkl.MKL_Get_Max_Threads()} threads"
    return rates
