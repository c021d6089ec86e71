"""Studies of many runs: the speed/accuracy trade-off (``tradeoff``), scene
sweeps on Dask (``sweep``) and the pieces they share (``runs``: reference
run, timed run, error measures)."""
