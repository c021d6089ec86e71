"""Files: time series for ParaView and Blender (``timeseries``), checkpoints
(``checkpoint``) and the one way every output is written, whole or not at
all (``files``)."""
