# %% [markdown]
# # The viewing pipeline in a notebook
#
# Every cell runs in Jupyter (a `Frame` shows itself inline: its `_repr_png_`) or as a plain
# script (`python docs/notebook.py`, which writes the pictures to `$NOTEBOOK_OUT`, default
# `notebook-out/`). A test runs it end to end (`tests/test_notebook.py`).

# %%
import os
from pathlib import Path

import numpy as np

from core import RenderSettings, render, render_file
from core.camera.view import n_per_factors
from core.inspect.buffers import buffer
from core.paths import SCENES_DIR
from core.scene.formats import load_scene

OUT = Path(os.environ.get("NOTEBOOK_OUT", "notebook-out"))
OUT.mkdir(parents=True, exist_ok=True)


def show(frame, name):
    """Inline in Jupyter (the cell's last value), a PNG beside the script otherwise."""
    (OUT / f"{name}.png").write_bytes(frame._repr_png_())
    return frame


# %% [markdown]
# ## The view and N_per, factor by factor (FvDFH 6.5)

# %%
scene = load_scene(SCENES_DIR / "house.toml", size=(240, 180))
view = scene.views[0]
factors = n_per_factors(view)
for name, m in factors.items():
    print(name, "=\n", np.round(m, 4) if np.ndim(m) else float(m))

# %% [markdown]
# ## The house as the course draws it: N_per, clipping, M_per, the midpoint line

# %%
show(render(scene, view, RenderSettings.for_scene(scene, size=(240, 180))), "house-wireframe")

# %% [markdown]
# ## A picture per shading stage: flat, Gouraud, Phong (FvDFH 16.2)

# %%
for shading in ("flat", "gouraud", "phong"):
    show(render_file(SCENES_DIR / "torus.toml", shading=shading, size=(160, 120)),
         f"torus-{shading}")

# %% [markdown]
# ## What the z-buffer kept: the depth buffer, as a picture

# %%
torus = load_scene(SCENES_DIR / "torus.toml", size=(160, 120))
values, picture = buffer(torus, torus.views[0], RenderSettings.for_scene(torus), "depth")
finite = values[np.isfinite(values)]
print(f"depth from {finite.min():.4f} to {finite.max():.4f} over {finite.size} pixels")
depth = render(torus, torus.views[0], RenderSettings.for_scene(torus))
depth.rgbx[:, :, :3] = picture
show(depth, "torus-depth")

# %% [markdown]
# ## The same scene ray traced (Whitted): shadows, mirrors and glass

# %%
show(render_file(SCENES_DIR / "whitted.toml", renderer="raytrace", size=(160, 120)),
     "whitted-raytraced")
