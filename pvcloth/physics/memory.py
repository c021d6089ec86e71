"""Refusing, before anything is allocated, a cloth the machine cannot hold."""

from __future__ import annotations

from pvcloth.errors import SceneError

#: Peak bytes per cloth point while a simulation is built: the stable-step
#: estimate's sparse Jacobians dominate (9.2 kB at 256x256, falling with size,
#: from `python benchmarks/memory.py`; stepping needs a tenth of it).
PEAK_BYTES_PER_POINT = 9200


def available_memory() -> float | None:
    """Bytes of memory available to a new allocation (Linux's MemAvailable),
    or None where that cannot be read."""
    try:
        with open("/proc/meminfo", encoding="ascii") as info:
            for line in info:
                if line.startswith("MemAvailable:"):
                    return 1024.0 * float(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_memory(scene) -> None:
    """Refuse, before any allocation, a cloth the machine cannot hold."""
    nx, ny = scene.cloth.resolution
    need = float(nx * ny * PEAK_BYTES_PER_POINT)
    have = available_memory()
    if have is not None and need > 0.9 * have:
        raise SceneError(
            "cloth.resolution",
            f"{nx} x {ny} = {nx * ny:,} points need about {need / 1e9:.3g} GB while the "
            f"simulation is built ({PEAK_BYTES_PER_POINT / 1e3:.1f} kB per point), and "
            f"{have / 1e9:.3g} GB are available. Use fewer points: about "
            f"{int((0.9 * have / PEAK_BYTES_PER_POINT) ** 0.5)} per side would fit.",
        )
