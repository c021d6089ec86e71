"""What the user sees: the cloth as a PyVista grid (``cloth_grid``) and its
view (``view``), drawn in the colours of ``colors`` with the obstacles of
``scenery``, framed by ``camera`` and ``framing``, on the GL window ``gl``
chooses; off-screen movies (``movie``), panels side by side (``compare``)
and the interactive window (``window``, with its physics thread
``window_physics`` and the mouse handling in ``interaction``). These read
the simulation; they never change its physics except through the
simulation's own methods."""
