"""What to simulate: validated, frozen scene descriptions and TOML loading
(``spec``), the value checks they use (``validation``) and the dotted-key
dialect every scene change is written in (``overrides``).

The scene layer depends on nothing else in pvcloth but :mod:`pvcloth.errors`.
The scene types are exported from ``pvcloth`` itself (``pvcloth.Scene``).
"""
