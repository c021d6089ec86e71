"""What an honest finiteness check costs in the compiled semi-implicit update.

The update kernel reports to the divergence guard whether every new value is
finite. Three builds of the same loop, timed interleaved in one process:

- ``isfinite under fast-math``: the earlier kernel. LLVM folded its
  ``np.isfinite`` test away, so it called NaN finite: fast and wrong.
- ``no fast-math``: the same loop with ``np.isfinite`` and no fast-math flags.
- ``checksum`` (pvcloth's kernel): fast-math kept; a running sum of the new
  values is finite exactly when each value is (reordering a sum cannot hide a
  NaN or an inf), tested once after the loop.

Each row also says whether the build finds a NaN placed in the positions.

Run:  python benchmarks/finite_check.py   (writes benchmarks/results/finite_check.md)
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numba
import numpy as np
from numba import prange
from provenance import provenance
from smoke import SMOKE

from pvcloth.physics import kernels

HERE = Path(__file__).parent
SIZES = (8,) if SMOKE else (64, 128, 256)
ROUNDS, CALLS = (1, 2) if SMOKE else (15, 50)


def _isfinite_kick(x3, v3, f3, inv_mass, dt, x_out, v_out):
    """The earlier kernel's loop: counts values that np.isfinite rejects."""
    ny, nx, _ = x3.shape
    fastest = 0.0
    bad = 0
    for j in prange(ny):
        for i in range(nx):
            w = dt * inv_mass[j, i]
            square = 0.0
            for d in range(3):
                vn = v3[j, i, d] + w * f3[j, i, d]
                xn = x3[j, i, d] + dt * vn
                v_out[j, i, d] = vn
                x_out[j, i, d] = xn
                square += vn * vn
                if not (np.isfinite(vn) and np.isfinite(xn)):
                    bad += 1
            fastest = max(fastest, square)
    return fastest, bad


BUILDS = {
    "isfinite under fast-math (earlier)": (
        numba.njit(fastmath=kernels.FASTMATH)(_isfinite_kick),
        lambda result: result[1] > 0,
    ),
    "isfinite, no fast-math": (numba.njit(_isfinite_kick), lambda result: result[1] > 0),
    "checksum under fast-math (pvcloth)": (
        kernels._KICK[0],
        lambda result: not math.isfinite(result[1]),
    ),
}


def main() -> None:
    rng = np.random.default_rng(0)
    rows = []
    for n in SIZES:
        x, v, f = (rng.random((n, n, 3)) for _ in range(3))
        inv_mass = rng.random((n, n))
        x_out, v_out = np.empty_like(x), np.empty_like(v)
        bad_x = x.copy()
        bad_x[n // 2, n // 3, 1] = np.nan
        times = {name: [] for name in BUILDS}
        found = {}
        for name, (kernel, says_bad) in BUILDS.items():
            kernel(x, v, f, inv_mass, 1e-4, x_out, v_out)  # compile
            found[name] = says_bad(kernel(bad_x, v, f, inv_mass, 1e-4, x_out, v_out))
        for _ in range(ROUNDS):
            for name, (kernel, _) in BUILDS.items():
                start = time.perf_counter()
                for _ in range(CALLS):
                    kernel(x, v, f, inv_mass, 1e-4, x_out, v_out)
                times[name].append((time.perf_counter() - start) / CALLS)
        base = float(np.median(times["isfinite under fast-math (earlier)"]))
        for name in BUILDS:
            ms = 1e3 * float(np.median(times[name]))
            rows.append((n, name, ms, ms / (1e3 * base), found[name]))
            print(f"{n:4d}  {name:<36} {ms:8.4f} ms  finds NaN: {found[name]}")
    lines = [
        "# Finiteness check in the compiled update",
        "",
        provenance(),
        "",
        f"`python benchmarks/finite_check.py` (serial builds), median of "
        f"{ROUNDS} rounds of {CALLS} calls, builds interleaved.",
        "",
        "| points per side | build | ms per call | ratio to the earlier kernel | finds a NaN |",
        "|---|---|---|---|---|",
        *(
            f"| {n} | {name} | {ms:.4f} | {ratio:.2f} | {'yes' if ok else 'NO'} |"
            for n, name, ms, ratio, ok in rows
        ),
        "",
    ]
    out = HERE / "results" / "finite_check.md"
    out.write_text("\n".join(lines))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
