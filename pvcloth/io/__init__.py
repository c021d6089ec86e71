"""Files: time series for ParaView and Blender (``timeseries``), checkpoints
(``checkpoint``) and the atomic writes both use (``files``)."""
