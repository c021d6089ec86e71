"""What to simulate: the validated, frozen scene (``spec``) and its parts
(``parts``), TOML scene files (``files``), the value checks they use
(``validation``), fabric presets (``materials``) and the dotted-key dialect
every scene change is written in (``overrides``).

The scene layer depends on nothing else in pvcloth but :mod:`pvcloth.errors`.
The scene types are exported from ``pvcloth`` itself (``pvcloth.Scene``).
"""
