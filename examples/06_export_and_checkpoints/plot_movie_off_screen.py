"""
An off-screen movie
===================

``pvcloth.render`` runs a simulation and draws every frame off-screen into
a GIF or an MP4 (or keeps the last one as a PNG), coloured by a field on
request, with the time, integrator and step in a corner. A GIF's frame
delays are whole centiseconds chosen to add up to the movie's length.
"""

# %%
# Render twenty frames
# --------------------
# ``color="speed"`` colours the cloth by its speed, with a scalar bar.
# ``progress=False`` hides the progress bar.
import tempfile
from pathlib import Path

import imageio.v3 as iio
import matplotlib.pyplot as plt
from PIL import Image

import pvcloth

scene = pvcloth.Scene(
    cloth=pvcloth.ClothSpec(resolution=(16, 16), orientation="horizontal", center=(0, 0, 1.5)),
    air_damping=1.0,
)
sim = pvcloth.Simulation(scene)
frames, fps = 20, 20
workdir = tempfile.TemporaryDirectory()  # removed when the script ends
stats = pvcloth.render(
    sim,
    Path(workdir.name) / "cloth.gif",
    frames=frames,
    fps=fps,
    size=(320, 240),
    color="speed",
    progress=False,
)
print(stats)

# %%
# What the file holds
# -------------------
# One picture per frame, and the simulation advanced by ``(frames - 1) /
# fps`` seconds: frame 0 is the state before any step.
movie = iio.imread(stats.path, index=None)
assert movie.shape[:3] == (frames, 240, 320)
assert abs(sim.time - (frames - 1) / fps) < 1e-12
# The delays (Pillow gives milliseconds, whole centiseconds in the file) add
# up to the movie's length: 20 frames at 20 a second, one second.
with Image.open(stats.path) as gif:
    delays = []
    for k in range(gif.n_frames):
        gif.seek(k)
        delays.append(gif.info["duration"])
assert sum(delays) == 1000 * frames / fps

# %%
# Four of its frames.
# sphinx_gallery_thumbnail_number = 2
fig, axes = plt.subplots(1, 4, figsize=(10, 2.2))
for ax, k in zip(axes, (0, 6, 12, 19), strict=True):
    ax.imshow(movie[k])
    ax.set_title(f"frame {k}", fontsize=9)
    ax.axis("off")
fig.tight_layout()
plt.show()
