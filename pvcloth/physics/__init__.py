"""The physics: model, state, forces, compiled kernels, obstacles, the
stability estimate, integrators and the simulation that drives them.

Nothing here imports a drawing, plotting, progress or scheduling library
(pyvista, vtk, matplotlib, tqdm, dask); ``tests/test_layers.py`` checks it.
"""
