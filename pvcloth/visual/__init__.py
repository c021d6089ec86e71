"""What the user sees: the cloth as a PyVista mesh and its view (``view``),
off-screen movies (``movie``), and the interactive window (``window``, with
its physics thread ``window_physics`` and the mouse handling in
``interaction``). These read the simulation; they never change its physics
except through the simulation's own methods."""
