"""``PVCLOTH_BENCHMARK_SMOKE=1`` shrinks every benchmark to a run of seconds
that only proves it still runs to the end (``tests/test_benchmarks.py``);
the numbers it then writes mean nothing and go to a copy of this folder."""

import os

SMOKE = os.environ.get("PVCLOTH_BENCHMARK_SMOKE") == "1"
