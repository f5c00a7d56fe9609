"""The notebook (docs/notebook.py, Jupyter's percent cells) run end to end as a script, and
a Frame's inline picture (``_repr_png_``) is its pixels exactly."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
PICTURES = ("house-wireframe", "torus-flat", "torus-gouraud", "torus-phong", "torus-depth",
            "whitted-raytraced")


def test_the_notebook_runs_and_draws_a_picture_per_stage(tmp_path):
    done = subprocess.run([sys.executable, str(ROOT / "docs" / "notebook.py")], cwd=tmp_path,
                          env={**os.environ, "NOTEBOOK_OUT": str(tmp_path / "out"),
                               "PYTHONPATH": str(ROOT)},
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "N_per =" in done.stdout and "z_min =" in done.stdout
    pictures = {}
    for name in PICTURES:
        with Image.open(tmp_path / "out" / f"{name}.png") as image:
            pictures[name] = np.asarray(image.convert("RGB"))
        assert len(np.unique(pictures[name].reshape(-1, 3), axis=0)) > 1, name
    assert pictures["house-wireframe"].shape == (180, 240, 3)
    # Gouraud and Phong differ where the highlight falls; flat shows its facets
    assert not np.array_equal(pictures["torus-gouraud"], pictures["torus-phong"])
    assert not np.array_equal(pictures["torus-flat"], pictures["torus-gouraud"])


def test_a_frame_shows_itself_as_its_own_pixels():
    from core import render_file
    frame = render_file(ROOT / "scenes" / "cube.toml", shading="gouraud", size=(64, 48))
    with Image.open(io.BytesIO(frame._repr_png_())) as image:
        assert image.format == "PNG"
        assert np.array_equal(np.asarray(image.convert("RGB")), frame.color)
