"""One pool at a time: BLAS runs on one thread while a step uses the kernels."""

from __future__ import annotations

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import pvcloth
from pvcloth.physics import kernels


def blas_threads() -> set[int]:
    return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def record_blas_threads_while_stepping(sim) -> list[set[int]]:
    seen = []
    step = sim.integrator.step

    def recording_step(*args, **kwargs):
        seen.append(blas_threads())
        return step(*args, **kwargs)

    sim.integrator.step = recording_step
    return seen


@pytest.mark.parametrize("integrator", ["implicit_euler", "backward_euler", "fast_mass_spring"])
def test_blas_is_held_to_one_thread_while_the_kernels_step(integrator):
    if not kernels.available():
        pytest.skip("numba is not installed")
    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    sim = pvcloth.Simulation(scene, integrator=integrator, backend="numba")
    seen = record_blas_threads_while_stepping(sim)
    with threadpool_limits(limits=2, user_api="blas"):  # the user's own setting
        sim.advance(2 * sim.dt)
        sim.step()
        assert blas_threads() == {2}  # given back after the step
    assert seen == [{1}] * 3


def test_the_numpy_path_leaves_blas_alone():
    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    sim = pvcloth.Simulation(scene, integrator="implicit_euler", backend="numpy")
    seen = record_blas_threads_while_stepping(sim)
    with threadpool_limits(limits=2, user_api="blas"):
        sim.advance(sim.dt)
    assert seen == [{2}]


def test_the_window_physics_thread_holds_blas_to_one_thread_on_the_numpy_path_too():
    import time

    from pvcloth.visual.window_physics import PhysicsThread

    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    sim = pvcloth.Simulation(scene, integrator="implicit_euler", backend="numpy")
    seen = record_blas_threads_while_stepping(sim)
    physics = PhysicsThread(sim, chunk_seconds=0.01)
    with threadpool_limits(limits=2, user_api="blas"):
        physics.start()
        deadline = time.perf_counter() + 20.0
        while not seen and time.perf_counter() < deadline:
            time.sleep(0.01)
        physics.stop()
        assert blas_threads() == {2}  # the thread gave the setting back
    assert seen and all(threads == {1} for threads in seen)


def test_explicit_steps_skip_the_limit():
    scene = pvcloth.Scene(cloth=pvcloth.ClothSpec(resolution=(8, 8)))
    sim = pvcloth.Simulation(scene, integrator="symplectic_euler")
    seen = record_blas_threads_while_stepping(sim)
    with threadpool_limits(limits=2, user_api="blas"):
        sim.step()
    assert seen == [{2}]
