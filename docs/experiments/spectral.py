"""pyamg's spectral-radius estimate for its Jacobi prolongation smoother, restart by restart.

Quoted by ``docs/studies/krylov.rst`` ("Noise"). pyamg's estimate of the spectral radius
of ``D^-1 S`` that weighs its prolongation smoother, on the displacement block of the
bench step's first tangent (scaled and in node blocks as
:class:`soilwater.linalg.krylov.Krylov` builds it): restarted Arnoldi, run by run
(``--products`` products each, restarted until the relative error is below
``--tolerance``): the restart vector's type, time, estimate and error, restarted as pyamg
restarts (from the complex Ritz vector) and from its real part.

``python docs/experiments/spectral.py 100000`` (the default size; about a minute on 2
cores).
"""

import time

import numpy as np
import scipy.sparse as sp

from soilwater.linalg.krylov import Krylov

from common import count, first_tangent, parsed, parser, scaled_tangent


def main(argv=None):
    """Estimate; return one row per size, restart kind and run (``rho``, ``error``)."""
    from pyamg.util.linalg import _approximate_eigenvalues
    from pyamg.util.utils import get_diagonal, scale_rows

    made = parser(__doc__)
    made.add_argument("sizes", nargs="*", type=count, default=[100_000],
                      help="requested node counts")
    made.add_argument("--products", type=count, default=15, help="Arnoldi products a run")
    made.add_argument("--runs", type=count, default=6, help="most runs per estimate")
    made.add_argument("--tolerance", type=float, default=0.01,
                      help="relative error the restarts stop at")
    rows = []
    with parsed(made, argv) as args:
        for nodes in args.sizes:
            K, layout = first_tangent(nodes, krylov=True)
            precondition = Krylov(K, layout)          # its displacement order and scales
            S = sp.bsr_matrix(scaled_tangent(K, precondition, precondition.sizes[0]),
                              blocksize=(2, 2))
            scaled = scale_rows(S, get_diagonal(S, inv=True), copy=True)   # as pyamg does
            for restart in ("complex", "real"):
                np.random.seed(0)
                v0 = np.random.rand(S.shape[0], 1)
                for run in range(args.runs):
                    tic = time.perf_counter()
                    vectors, values, H, V, _ = _approximate_eigenvalues(
                        scaled, args.products, False, initial_guess=v0 / np.linalg.norm(v0))
                    top = np.abs(values).argmax()
                    error = abs(H[len(values), len(values) - 1] * vectors[-1, top]
                                / values[top])
                    row = {"nodes": nodes, "restart": restart, "run": run,
                           "vector": str(V[0].dtype), "seconds": time.perf_counter() - tic,
                           "rho": float(abs(values[top])), "error": float(error)}
                    print(f"{nodes} nodes, {restart} restarts, run {run}: vector "
                          f"{row['vector']}, {row['seconds']:.2f} s, rho {row['rho']:.5f}, "
                          f"relative error {error:.2g}", flush=True)
                    rows.append(row)
                    if error < args.tolerance:
                        break
                    v0 = np.hstack(V[:-1]) @ vectors[:, top].reshape(-1, 1)
                    if restart == "real":             # the Ritz vector's phase removed
                        v0 = np.real(v0 * np.exp(-1j * np.angle(v0[np.abs(v0).argmax()])))
    return rows


if __name__ == "__main__":
    main()
