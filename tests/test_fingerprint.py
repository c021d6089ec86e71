"""Fingerprints: every bundled scene with every integrator, at 8x8 points
(and the hanging cloth with a tolerance and with substeps, which no bundled
scene uses), lands after a few steps where it landed when the fingerprints
were recorded (``tests/data/fingerprints.npz``). A change meant to change nothing for a
user (a refactor) must keep them; a change of the physics re-records them
and says why in its commit::

    python tests/test_fingerprint.py record

On the machine and library versions that recorded them the positions must
match bit for bit; elsewhere (another CPU's vector instructions round
fast-math sums differently) within 1e-8 m, a thousand times what rounding
moves a point in these few steps and far below what any change of the
physics does (1e-6 m for implicit_euler, whose iterative linear solve
stops where the rounding lets it: see ``ELSEWHERE_CG``). A scene an
integrator cannot run (a refused step, a tolerance it cannot measure) is
recorded as the error's message, which must stay the same too.
"""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import numpy as np
import pytest

import pvcloth
from pvcloth import PvclothError, Simulation
from pvcloth.physics.integrators import INTEGRATORS

HERE = Path(__file__).resolve().parent
RECORD = HERE / "data" / "fingerprints.npz"
SCENES = sorted((HERE.parent / "data" / "scenes").glob("*.toml"))
#: Points a side and steps per run: small enough that all 104 runs take a
#: few seconds, and small grids step on the serial kernels (threads would
#: make the sums' order, and so the last bits, depend on the thread count).
SIZE, STEPS = 8, 12
#: Where another machine's results may differ (m).
ELSEWHERE = 1e-8
#: The same for implicit_euler, whose conjugate-gradient solve stops at a
#: relative residual of 1e-8: where it stops depends on the rounding (an
#: iteration more or fewer), so another CPU moves its points by about that
#: share of a step's change, and contact can carry it on (measured: 1.1e-8 m
#: in the crumple and 9e-11 m on the cotton, on an Intel CPU against the
#: AMD one that recorded them; every other integrator within 1e-13 m).
ELSEWHERE_CG = 1e-6


def machine() -> str:
    """What decides the last bits: the CPU the kernels are compiled for and
    the versions of the libraries that compute."""
    import llvmlite.binding
    import numba
    import scipy

    return (
        f"{platform.machine()} {llvmlite.binding.get_host_cpu_name()}, numpy {np.__version__}, "
        f"numba {numba.__version__}, scipy {scipy.__version__}"
    )


#: Settings the bundled scenes do not use, run on the hanging cloth so that
#: the adaptive controller and the substep policy are fingerprinted too.
VARIANTS = {
    "tolerance": {"solver.tolerance": 1e-3, "solver.dt": None},
    "substeps": {"solver.dt": 0.01, "solver.stability": "substep"},
}


def fingerprint(path: Path, integrator: str, variant: str = "") -> np.ndarray | str:
    """Positions (m), shape (SIZE * SIZE, 3), after STEPS steps of the
    scene at SIZE x SIZE points with the integrator at the scene's step
    (its ``solver.dt``, or the automatic one where it gives none); or the
    message of the error that refused it."""
    scene = pvcloth.load_scene(path)
    try:
        scene = scene.with_overrides(
            {"cloth.resolution": [SIZE, SIZE], **VARIANTS.get(variant, {})}
        )
        sim = Simulation(scene, integrator=integrator)
        for _ in range(STEPS):
            sim.step()
    except PvclothError as error:
        return f"{type(error).__name__}: {error}"
    return sim.positions.copy()


HANGING = HERE.parent / "data" / "scenes" / "hanging.toml"
CASES = [(p, name, "") for p in SCENES for name in sorted(INTEGRATORS)] + [
    (HANGING, name, variant) for variant in VARIANTS for name in sorted(INTEGRATORS)
]


def _key(path: Path, integrator: str, variant: str = "") -> str:
    return f"{path.stem}{'+' + variant if variant else ''}/{integrator}"


def record() -> None:
    kept = {"machine": np.array(machine())}
    for case in CASES:
        found = fingerprint(*case)
        kept[_key(*case)] = np.array(found)
        print(_key(*case), "refused" if isinstance(found, str) else "ok")
    partial = RECORD.with_suffix(".partial.npz")
    RECORD.parent.mkdir(exist_ok=True)
    np.savez_compressed(partial, **kept)
    partial.replace(RECORD)
    print(f"recorded {len(CASES)} fingerprints in {RECORD.relative_to(HERE.parent)}")


@pytest.fixture(scope="module")
def recorded():
    with np.load(RECORD) as kept:
        return {key: kept[key] for key in kept.files}


def test_every_bundled_scene_and_integrator_has_a_fingerprint(recorded):
    assert sorted(k for k in recorded if k != "machine") == sorted(_key(*c) for c in CASES)


@pytest.mark.parametrize("path, integrator, variant", CASES, ids=[_key(*c) for c in CASES])
def test_the_steps_land_where_they_did_when_recorded(recorded, path, integrator, variant):
    was = recorded[_key(path, integrator, variant)]
    now = fingerprint(path, integrator, variant)
    if was.dtype.kind == "U":  # refused then: refused now, with the same words
        assert now == str(was)
        return
    assert not isinstance(now, str), now
    assert np.isfinite(now).all()
    if str(recorded["machine"]) == machine():
        np.testing.assert_array_equal(now, was)  # bit for bit
    else:
        near = ELSEWHERE_CG if integrator == "implicit_euler" else ELSEWHERE
        np.testing.assert_allclose(now, was, rtol=0.0, atol=near)


if __name__ == "__main__":
    if sys.argv[1:] != ["record"]:
        sys.exit("usage: python tests/test_fingerprint.py record")
    record()
